// `confpack analyze` (apps/cmd_analyze.cpp) end to end: a packing file with a known answer in,
// result.json and the CSV profiles out; a bad file refused with exit code 2 and nothing written;
// SIGTERM stops a long analysis.
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <thread>

#include "core/packing_io.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/lattices.hpp"
#include "tests/support/read_file.hpp"

using namespace confpack;
namespace fs = std::filesystem;
using confpack::testing::ConfpackSession;
using confpack::testing::lineCount;

TEST_CASE("confpack analyze writes result.json and profiles", "[apps][cli]") {
  const ConfpackSession s("cmd_analyze");
  const fs::path& dir = s.dir;
  core::Packing p = confpack::testing::simpleCubic(5, 4, 10);
  p.box.periodicY = false;
  // Contacts with forces: then the equilibrium block is evaluated (zero velocities). Gravity is
  // not balanced by these forces, so it must say "not reached".
  core::Contact c;
  c.a = 0;
  c.b = 1;
  c.normal = core::Vec3::UnitX();
  c.points.push_back({core::Vec3(1.0, 0.5, 0.5), 0.3});
  p.contacts = std::vector<core::Contact>{c};
  core::writePacking(p, dir / "packing.json");

  REQUIRE(s.run("analyze packing.json --out res --quiet").code == 0);
  std::ifstream in(dir / "res" / "result.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  CHECK(j["n_grains"] == 200);
  CHECK(j["solid_fraction"].get<double>() == Approx(std::numbers::pi / 6).epsilon(1e-12));
  CHECK(j["coordination"]["geometric_contacts"] == false);
  CHECK(j["equilibrium"]["reached"] == false);
  CHECK(j["equilibrium"]["velocities"] == "assumed_zero");
  CHECK(j["nematic"]["bulk"].is_null());
  for (const char* f : {"phi_y.csv", "z_y.csv", "homogeneity_z.csv", "homogeneity_y.csv", "orientation_cos.csv",
                        "orientation_azimuth.csv"})
    CHECK(fs::exists(dir / "res" / f));

  // Bad input: exit 2, no output directory.
  {
    std::ofstream bad(dir / "bad.json");
    bad << R"({"format": "confpack-packing", "version": 1, "box": {"length_x": -1}, "grains": []})";
  }
  CHECK(s.run("analyze bad.json --out bad_out").code == 2);
  CHECK_FALSE(fs::exists(dir / "bad_out"));
  CHECK(s.run("analyze missing.json --out missing_out").code == 2);
  CHECK_FALSE(fs::exists(dir / "missing_out"));
  CHECK(s.run("analyze packing.json --out neg --slice -1").code == 2);
  CHECK_FALSE(fs::exists(dir / "neg"));
  // A slice far too thin (issue 23, failure 6): one line, exit 2, nothing written, at once.
  const auto thin = s.run("analyze packing.json --out thin --slice 1e-7");
  CHECK(thin.code == 2);
  CHECK(thin.err ==
        "confpack analyze: error: analysis: about 8e+09 cells (200 grains x phi(y) slices of 1e-07 d_L), more than "
        "max_cells (2e+08); check the slice or cell size, or raise the limit with --max-cells\n");
  CHECK_FALSE(fs::exists(dir / "thin"));
  CHECK(s.run("analyze packing.json --out low --max-cells 39999").code == 2);
  CHECK_FALSE(fs::exists(dir / "low"));
  CHECK(s.run("analyze packing.json --out raised --max-cells 40000 --quiet").code == 0);
  CHECK(s.run("analyze packing.json --out bad_limit --max-cells 0").code == 2);
}

TEST_CASE("confpack analyze refuses an implausible packing by name, exit 2, unless --allow-implausible",
          "[apps][cli]") {
  const ConfpackSession s("cmd_analyze_implausible");
  // A sphere of size 100 in a 5 x 5 box.
  core::Packing big;
  big.box.lengthX = 5.0;
  big.box.width = 5.0;
  big.grains.push_back(confpack::testing::sphere(100.0, core::Vec3(2.5, 2.5, 50.0)));
  core::writePacking(big, s.dir / "big.json");
  // Every grain of a touching lattice doubled in size: 64 spheres of volume 4 pi / 3 in
  // 4 x 4 x 4.5 (up to the top of the highest), phi = 3.7.
  core::Packing doubled = confpack::testing::simpleCubic(4, 4, 4);
  doubled.box.height = 4.0;
  for (core::Grain& g : doubled.grains) g.size *= 2.0;
  core::writePacking(doubled, s.dir / "doubled.json");
  // A contact between two grains 3 d apart.
  core::Packing apart = confpack::testing::simpleCubic(8, 4, 1);
  core::Contact c;
  c.a = 0;
  c.b = 3;  // centres at x = 0.5 and 3.5
  c.normal = core::Vec3::UnitX();
  c.points.push_back({core::Vec3(1.0, 0.5, 0.5), 0.3, core::Vec3::Zero(), 0.0});
  apart.contacts = std::vector<core::Contact>{c};
  core::writePacking(apart, s.dir / "apart.json");

  const std::vector<std::pair<std::string, std::string>> cases = {
      {"big.json", "big.json: implausible packing: grain 0 (size 100) is larger than the box's period L_x (5)"},
      {"doubled.json", "doubled.json: implausible packing: the grains' volume"},
      {"apart.json", "apart.json: implausible packing: contacts[0] has a point"},
  };
  for (const auto& [file, message] : cases) {
    INFO(file);
    const auto r = s.run("analyze " + file + " --out res");
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(lineCount(r.err) == 1);
    CHECK(r.err.find("confpack analyze: error: " + message) != std::string::npos);
    CHECK(r.err.find("--allow-implausible") != std::string::npos);
    CHECK_FALSE(fs::exists(s.dir / "res"));
  }
  // run --from reads a packing for the same analysis: the same refusal.
  const auto from = s.run("run --from doubled.json --out res");
  CHECK(from.code == 2);
  CHECK(from.err.find("doubled.json: implausible packing") != std::string::npos);
  CHECK_FALSE(fs::exists(s.dir / "res"));

  // Asked for, they are analysed all the same.
  CHECK(s.run("analyze doubled.json --out res1 -q --allow-implausible").code == 0);
  CHECK(s.run("analyze apart.json --out res2 -q --allow-implausible").code == 0);
  CHECK(fs::exists(s.dir / "res2" / "result.json"));
  CHECK(s.run("analyze --help").out.find("--allow-implausible") != std::string::npos);
}

TEST_CASE("grains that share one centre are refused as implausible by analyze and run --from", "[apps][cli]") {
  // The failure this guards against: 91 spheres at [1,1,1] analysed with exit 0 and overlapping_pairs 0.
  const ConfpackSession s("cmd_analyze_one_centre");
  core::Packing p;
  p.box.lengthX = p.box.width = 6.0;
  p.box.height = 6.0;
  core::Grain g;
  g.position = core::Vec3(1.0, 1.0, 1.0);
  p.grains.assign(91, g);
  core::writePacking(p, s.dir / "one-centre.json");
  for (const char* command : {"analyze one-centre.json --out res", "run --from one-centre.json --out res"}) {
    INFO(command);
    const auto r = s.run(command);
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(lineCount(r.err) == 1);
    CHECK(r.err.find("one-centre.json: implausible packing: grain 0 and grain 1 overlap by 1 ") != std::string::npos);
    CHECK_FALSE(fs::exists(s.dir / "res"));
  }
}

TEST_CASE("analyze reads regular files only: a FIFO, a device or a folder is refused at once by name", "[apps][cli]") {
  // The failure this guards against: a FIFO blocked for ever, /dev/zero and /dev/urandom grew memory without
  // bound and ignored SIGTERM. Each must be refused (exit 2) within seconds.
  const ConfpackSession s("cmd_analyze_kinds");
  REQUIRE(::mkfifo((s.dir / "fifo").c_str(), 0600) == 0);
  fs::create_directory(s.dir / "folder");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"fifo", "fifo: is a FIFO, not a regular file"},
      {"/dev/zero", "/dev/zero: is a character device, not a regular file"},
      {"/dev/urandom", "/dev/urandom: is a character device, not a regular file"},
      {"folder", "folder: is a folder, not a packing file"},
  };
  const fs::path err = s.dir.string() + ".err";
  for (const auto& [file, message] : cases) {
    INFO(file);
    const pid_t pid = confpack::testing::startConfpack(s.dir, {"analyze", file, "--out", "res", "-q"}, err);
    REQUIRE(pid >= 0);
    int status = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        FAIL("still reading after 20 s");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    const std::string message_ = confpack::testing::slurp(err);
    INFO("stderr: " << message_);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 2);
    CHECK(lineCount(message_) == 1);
    CHECK(message_.find("confpack analyze: error: " + message) != std::string::npos);
    CHECK_FALSE(fs::exists(s.dir / "res"));
  }
  fs::remove(err);
}

TEST_CASE("a --slice finer than a profile can hold is refused by name, not replaced by one slice", "[apps][cli]") {
  // The failure this guards against: --slice 1e-9 --max-cells 1e300 exited 0 with a single slice (# slice: 4).
  const ConfpackSession s("cmd_analyze_fine_slice");
  core::Packing p = confpack::testing::simpleCubic(5, 4, 10);
  p.box.periodicY = false;
  core::writePacking(p, s.dir / "p.json");
  const auto r = s.run("analyze p.json --slice 1e-9 --max-cells 1e300 --out res");
  INFO("stderr: " << r.err);
  CHECK(r.code == 2);
  CHECK(lineCount(r.err) == 1);
  CHECK(r.err.find("confpack analyze: error: profile: slice of 1e-09 d_L over 4 d_L makes 4e+09 cells") !=
        std::string::npos);
  CHECK_FALSE(fs::exists(s.dir / "res"));
}

TEST_CASE("analyze --inflate and --type-band are recorded in result.json, and refused out of range by name, exit 2",
          "[apps][cli]") {
  const ConfpackSession s("cmd_analyze_readings");
  core::writePacking(confpack::testing::simpleCubic(6, 5, 12), s.dir / "p.json");
  REQUIRE(s.run("analyze p.json --out res --inflate 1.2 --type-band 0.1 -q").code == 0);
  std::ifstream in(s.dir / "res" / "result.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  CHECK(j["inflate"] == 1.2);
  CHECK(j["analysis_options"]["inflate"] == 1.2);
  CHECK(j["analysis_options"]["type_band"] == 0.1);
  CHECK(j["coordination_band"]["band"] == 0.1);
  CHECK(j["coordination"]["geometric_contacts"] == true);
  // The inflated lattice: every grain overlaps its six neighbours, phi about 1.2^3 pi / 6.
  CHECK(j["coordination"]["Z"].get<double>() == Approx(6.0));
  CHECK(j["solid_fraction"].get<double>() == Approx(1.728 * std::numbers::pi / 6).epsilon(0.01));
  CHECK(j["interpenetration_percent"]["exact"].get<double>() > 0.0);
  // The default: the exact reading, no band.
  REQUIRE(s.run("analyze p.json --out plain -q").code == 0);
  std::ifstream plainIn(s.dir / "plain" / "result.json");
  const nlohmann::json plain = nlohmann::json::parse(plainIn);
  CHECK(plain["inflate"] == 1.0);
  CHECK(plain["analysis_options"]["type_band"].is_null());
  CHECK(plain["coordination_band"].is_null());

  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--inflate 0.99", "--inflate: must be a factor in [1, 1.5] (got 0.99)"},
      {"--inflate 1.6", "--inflate: must be a factor in [1, 1.5] (got 1.6)"},
      {"--inflate nan", "--inflate: must be a factor in [1, 1.5] (got 'nan', not a finite number)"},
      {"--inflate inf", "--inflate: must be a factor in [1, 1.5] (got 'inf', not a finite number)"},
      {"--type-band 0", "--type-band: must be a fraction in (0, 0.5] (got 0)"},
      {"--type-band -0.1", "--type-band: must be a fraction in (0, 0.5] (got -0.1)"},
      {"--type-band 0.6", "--type-band: must be a fraction in (0, 0.5] (got 0.6)"},
      {"--type-band nan", "--type-band: must be a fraction in (0, 0.5] (got 'nan', not a finite number)"},
  };
  for (const auto& [option, message] : cases) {
    INFO(option);
    const auto r = s.run("analyze p.json --out bad " + option);
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(lineCount(r.err) == 1);
    CHECK(r.err == "confpack analyze: error: " + message + " (see --help)\n");
    CHECK_FALSE(fs::exists(s.dir / "bad"));
  }
}

TEST_CASE("packings written by runs of either backend are plausible", "[apps][cli]") {
  const ConfpackSession s("cmd_analyze_real_runs");
  for (const char* backend : {"nscd", "bullet"}) {
    INFO(backend);
    const std::string dir = std::string("run_") + backend;
    const auto run = s.run("run --length-x 4 --width 4 --height 4 --time-limit 4 --wall-friction 0.3 -q --backend " +
                           std::string(backend) + " --out " + dir);
    REQUIRE(run.code == 0);
    REQUIRE(core::readPacking(s.dir / dir / "packing.json").contacts->size() > 50);
    const auto r = s.run("analyze " + dir + "/packing.json --out " + dir + "_analysis -q");
    INFO("stderr: " << r.err);
    CHECK(r.code == 0);
  }
}

TEST_CASE("SIGTERM stops a long analysis: one line saying where, exit 143, nothing written", "[apps][cli]") {
  const ConfpackSession s("cmd_analyze_sigterm");
  REQUIRE(s.run("deposit --length-x 5 --width 5 --height 6 --out dep -q").code == 0);
  const fs::path err = s.dir.string() + ".err";
  // 170 grains and 250,000 slices of phi(y): some 10 s of work (mostly the profile fit), stopped
  // after one.
  const pid_t pid = confpack::testing::startConfpack(
      s.dir, {"analyze", "dep/packing.json", "--slice", "2e-5", "--out", "out", "-q"}, err);
  REQUIRE(pid >= 0);
  const confpack::testing::Stopped stopped =
      confpack::testing::stopAfter(pid, std::chrono::milliseconds(1000), SIGTERM, err);
  const int status = stopped.status;
  const std::string& message = stopped.message;
  INFO(message);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 143);
  CHECK(lineCount(message) == 1);
  CHECK(message.find("confpack analyze: error: interrupted by SIGTERM while ") != std::string::npos);
  CHECK(s.entries() == std::vector<std::string>{"dep"});  // neither out/ nor its staging folder
}

TEST_CASE("SIGTERM stops the reading of a large input file: one line naming the file, exit 143", "[apps][cli]") {
  // The failure this guards against: a signal was only seen once the whole document was parsed
  // (about a minute for a file of 2 GiB). 150 MB of JSON takes several seconds to parse; the
  // document is no packing, so had the signal waited for the parse, the exit would be 2.
  const ConfpackSession s("cmd_analyze_sigterm_reading");
  {
    std::ofstream big(s.dir / "big.json");
    const std::string row = "[0.125, 0.25, 0.5],";
    big << "[";
    for (std::size_t written = 0; written < (std::size_t{150} << 20); written += row.size()) big << row;
    big << "[0]]";
  }
  const fs::path err = s.dir.string() + ".err";
  const pid_t pid = confpack::testing::startConfpack(s.dir, {"analyze", "big.json", "--out", "out", "-q"}, err);
  REQUIRE(pid >= 0);
  const confpack::testing::Stopped stopped =
      confpack::testing::stopAfter(pid, std::chrono::milliseconds(500), SIGTERM, err);
  INFO(stopped.message);
  REQUIRE(WIFEXITED(stopped.status));
  CHECK(WEXITSTATUS(stopped.status) == 143);
  CHECK(lineCount(stopped.message) == 1);
  CHECK(stopped.message.find("interrupted by SIGTERM while reading big.json") != std::string::npos);
  CHECK_FALSE(fs::exists(s.dir / "out"));
}
