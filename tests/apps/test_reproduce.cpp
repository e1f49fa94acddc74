// `confpack reproduce` and `confpack sweep` with the real binary and real physics: the study
// definitions of SPEC 7, a sweep killed with SIGKILL and resumed, and the tiny scale end to end.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "study/reproduce.hpp"
#include "study/sweep.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using nlohmann::json;

namespace {

using confpack::testing::slurp;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_repro_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

int runConfpack(const fs::path& dir, const std::string& args) {
  const std::string cmd = "cd '" + dir.string() + "' && '" + CONFPACK_BINARY + "' " + args + " > out.txt 2> err.txt";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST_CASE("reproduce: the paper scale is the SPEC 7 study") {
  const auto runs = study::expandRuns(study::parseSweepSpec(study::reproductionSweep("paper")));
  // Spheres x_S x {5, 10, 20, bi}: 4 x 4; MSP wall friction {0.3, 0.5, 1} x {5, 10, 20}: 9;
  // pinacoids x {5, 10, 20, bi}: 4. Each with 3 seeds and 2 backends.
  CHECK(runs.size() == (16 + 9 + 4) * 3 * 2);
  std::set<double> widths, fractions, frictions;
  std::map<std::size_t, std::set<std::string>> backendsOfDeposit;
  for (const auto& r : runs) {
    CHECK(r.config.box.lengthX == 20.0);
    CHECK(r.config.box.height == 16.0);
    if (!r.config.box.periodicY)
      widths.insert(r.config.box.width);
    else
      CHECK(r.config.box.width == 20.0);
    fractions.insert(r.config.population.smallFraction);
    frictions.insert(r.config.box.wallFriction);
    if (r.config.box.wallFriction > 0.0) {
      CHECK(r.config.population.shape == core::ShapeKind::Sphere);
      CHECK(r.config.population.smallFraction == 0.0);
    }
    if (r.config.population.shape == core::ShapeKind::Pinacoid) CHECK(r.config.population.smallFraction == 0.0);
    backendsOfDeposit[r.depositIndex].insert(r.config.backend);
  }
  CHECK(widths == std::set<double>{5.0, 10.0, 20.0});
  CHECK(fractions == std::set<double>{0.0, 10.0, 25.0, 40.0});
  CHECK(frictions == std::set<double>{0.0, 0.3, 0.5, 1.0});
  for (const auto& [d, b] : backendsOfDeposit) CHECK(b == std::set<std::string>{"nscd", "bullet"});
  // quick and tiny are smaller studies of the same kinds; an unknown scale is refused.
  const auto quick = study::expandRuns(study::parseSweepSpec(study::reproductionSweep("quick")));
  CHECK(quick.size() < runs.size());
  // The quick study brings its nscd runs to rest with the finisher (docs/model.md).
  for (const study::SweepRun& r : quick) CHECK(r.config.compaction.protocol == core::Protocol::QuasiStatic);
  CHECK(study::expandRuns(study::parseSweepSpec(study::reproductionSweep("tiny"))).size() == 6);
  CHECK_THROWS_AS(study::reproductionSweep("huge"), std::invalid_argument);
}

TEST_CASE("a sweep killed with SIGKILL and restarted finishes with no run lost or redone") {
  const fs::path dir = scratch("kill");
  // Four small, short runs of real physics (the time limit, not equilibrium, ends them).
  std::ofstream(dir / "s.json") << R"({
    "name": "kill",
    "base": { "box": { "length_x": 3, "height": 3 }, "compaction": { "time_limit": 1.5 } },
    "vary": { "width": [3, 4], "seed": [1], "backend": ["nscd", "bullet"] } })";
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) _exit(127);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl(CONFPACK_BINARY, CONFPACK_BINARY, "sweep", "s.json", "--out", "sw", "--jobs", "1", (char*)nullptr);
    _exit(127);
  }
  // Kill as soon as the first run is finished (the second is then in progress or about to be).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(dir / "sw" / "runs" / "r0000" / study::kDoneMarker) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(fs::exists(dir / "sw" / "runs" / "r0000" / study::kDoneMarker));

  std::map<std::string, std::string> markers;  // finished before the kill: content must not change
  for (const auto& e : fs::directory_iterator(dir / "sw" / "runs"))
    if (fs::exists(e.path() / study::kDoneMarker))
      markers[e.path().filename().string()] = slurp(e.path() / study::kDoneMarker);
  INFO("finished before the kill: " << markers.size());
  CHECK(markers.size() < 4);

  REQUIRE(runConfpack(dir, "sweep s.json --out sw") == 0);
  const std::string out = slurp(dir / "out.txt");
  CHECK(out.find(std::to_string(markers.size()) + " earlier") != std::string::npos);
  for (const char* r : {"r0000", "r0001", "r0002", "r0003"}) {
    INFO(r);
    CHECK(study::runStatus(dir / "sw" / "runs" / r) == study::RunStatus::Done);
    CHECK(fs::exists(dir / "sw" / "runs" / r / "result.json"));
  }
  for (const auto& [name, text] : markers) CHECK(slurp(dir / "sw" / "runs" / name / study::kDoneMarker) == text);
  // Both backends of a pile read the same deposit file.
  CHECK(fs::exists(dir / "sw" / "deposits" / "d0000.json"));
  CHECK(fs::exists(dir / "sw" / "deposits" / "d0001.json"));
  fs::remove_all(dir);
}

TEST_CASE("reproduce --scale tiny: the whole chain to a report") {
  const fs::path dir = scratch("tiny");
  const auto t0 = std::chrono::steady_clock::now();
  const int code = runConfpack(dir, "reproduce --scale tiny --out tiny --jobs 2");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO("stderr: " << slurp(dir / "err.txt"));
  REQUIRE(code == 0);
  WARN("reproduce --scale tiny took " << seconds << " s");
  const std::string md = slurp(dir / "tiny" / "report" / "report.md");
  const std::string html = slurp(dir / "tiny" / "report" / "report.html");
  CHECK(md.find("# confpack study report: tiny") != std::string::npos);
  CHECK(md.find("| r0005 |") != std::string::npos);
  CHECK(md.find("### solid_fraction") != std::string::npos);
  CHECK(md.find("nscd − bullet") != std::string::npos);
  CHECK(html.find("</html>") != std::string::npos);
  for (int i = 0; i < 6; ++i) {
    char name[8];
    std::snprintf(name, sizeof name, "r%04d", i);
    CHECK(study::runStatus(dir / "tiny" / "runs" / name) == study::RunStatus::Done);
  }
  // Running it again finds everything done and only rewrites the report.
  REQUIRE(runConfpack(dir, "reproduce --scale tiny --out tiny") == 0);
  CHECK(slurp(dir / "out.txt").find("0 finished now, 6 earlier") != std::string::npos);
  fs::remove_all(dir);
}
