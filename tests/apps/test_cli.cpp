// The `confpack` command line, run as a user runs it (the real binary, CONFPACK_BINARY), and the
// run configuration it writes back.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "backends/backend_factory.hpp"
#include "core/packing_io.hpp"
#include "core/run_config.hpp"
#include "tests/support/read_file.hpp"

using namespace confpack;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using confpack::testing::slurp;

struct Result {
  int code = -1;
  std::string out, err;
};

/// A scratch directory per test case, removed at the end.
struct Scratch {
  fs::path dir;
  explicit Scratch(const std::string& name)
      : dir(fs::temp_directory_path() / ("confpack_test_cli_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() { fs::remove_all(dir); }
  /// Runs `confpack <args>` inside the scratch directory (stdout and stderr captured).
  Result run(const std::string& args) const {
    const std::string cmd =
        "cd '" + dir.string() + "' && '" + std::string(CONFPACK_BINARY) + "' " + args + " > stdout.txt 2> stderr.txt";
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir / "stdout.txt");
    r.err = slurp(dir / "stderr.txt");
    fs::remove(dir / "stdout.txt");
    fs::remove(dir / "stderr.txt");
    return r;
  }
  /// Entries of the scratch directory (to check that nothing was written).
  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
    return out;
  }
};

int lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

}  // namespace

TEST_CASE("every subcommand has --help") {
  Scratch s("help");
  const Result root = s.run("--help");
  CHECK(root.code == 0);
  for (const char* sub : {"deposit", "run", "analyze", "sweep", "report", "reproduce", "bench"}) {
    INFO(sub);
    CHECK(root.out.find(sub) != std::string::npos);
    const Result r = s.run(std::string(sub) + " --help");
    CHECK(r.code == 0);
    CHECK(r.out.find("Usage: confpack " + std::string(sub)) != std::string::npos);
  }
  const Result deposit = s.run("deposit --help");
  for (const char* flag : {"--shape", "--length-x", "--width", "--periodic-y", "--height", "--small-fraction",
                           "--wall-friction", "--backend", "--seed", "--out", "--threads", "--quiet", "-v"})
    CHECK(deposit.out.find(flag) != std::string::npos);
  CHECK(s.entries().empty());
}

TEST_CASE("bad input is refused with one line, exit 2 and no output directory") {
  Scratch s("bad");
  const std::string valid = "--length-x 6 --width 4 --height 4 --out out";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"deposit --bogus " + valid, "--bogus"},
      {"deposit --backend foo " + valid, "--backend"},
      {"deposit " + valid + " --width 0", "--width"},
      {"deposit " + valid + " --width -3", "--width"},
      {"deposit " + valid + " --small-fraction 120", "--small-fraction"},
      {"deposit " + valid + " --small-fraction -1", "--small-fraction"},
      {"deposit " + valid + " --length-x abc", "--length-x"},
      {"deposit " + valid + " --height nan", "--height"},
      {"deposit " + valid + " --wall-friction -0.1", "--wall-friction"},
      {"deposit " + valid + " --seed -1", "--seed"},
      {"deposit " + valid + " --threads 0", "--threads"},
      {"deposit " + valid + " --shape cube", "--shape"},
      {"deposit " + valid + " --pinacoid-alpha 90", "--pinacoid-alpha"},
      {"run " + valid + " --protocol static", "--protocol"},
      {"run " + valid + " --switch-kinetic-ratio 0", "--switch-kinetic-ratio"},
      {"deposit --length-x 6", "--out"},                                      // missing --out
      {"deposit " + valid + " --shape pinacoid --pinacoid-E 3", "pinacoid"},  // no ridge: refused by validate()
      {"", "subcommand"},
      {"frobnicate", "frobnicate"},
  };
  for (const auto& [args, mention] : cases) {
    INFO("confpack " << args);
    const Result r = s.run(args);
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(lines(r.err) == 1);
    CHECK(r.err.find(mention) != std::string::npos);
    CHECK(r.out.empty());
    CHECK(s.entries().empty());  // nothing created, not even the directory
  }
  // An --out that is a file: refused as bad input, the file untouched.
  std::ofstream(s.dir / "file") << "keep";
  const Result r = s.run("deposit --length-x 6 --width 4 --height 4 --out file");
  CHECK(r.code == 2);
  CHECK(lines(r.err) == 1);
  CHECK(slurp(s.dir / "file") == "keep");
}

TEST_CASE("every subcommand refuses an unknown flag with one line and exit 2") {
  // A placeholder answers "not implemented yet"; a real subcommand refuses the flag at parse time.
  // Either way nothing runs (no real work in this test: a default `run` would take minutes).
  Scratch s("unknown_flag");
  for (const char* sub : {"deposit", "run", "analyze", "sweep", "report", "reproduce", "bench"}) {
    INFO(sub);
    const Result r = s.run(std::string(sub) + " --no-such-flag-for-tests");
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(lines(r.err) == 1);
    CHECK(s.entries().empty());
  }
}

TEST_CASE("a small deposit writes a readable packing inside the box, its config and a ParaView series") {
  Scratch s("deposit");
  const Result r = s.run("deposit --length-x 6 --width 4 --height 4 --seed 3 --wall-friction 0.3 --out a/dep");
  INFO("stderr: " << r.err);
  REQUIRE(r.code == 0);
  CHECK(lines(r.out) == 1);  // the one-line summary
  CHECK(r.out.find("grains") != std::string::npos);
  const fs::path dir = s.dir / "a" / "dep";

  const core::Packing p = core::readPacking(dir / "packing.json");
  CHECK_FALSE(p.contacts.has_value());  // a deposit has no forces yet
  CHECK(p.box.lengthX == 6.0);
  CHECK(p.box.width == 4.0);
  CHECK(p.box.wallFriction == 0.3);
  REQUIRE(p.grains.size() > 10);
  // Inside the box: x in [0, L_x), and the whole sphere between the walls and above the floor
  // (a deposit overlaps nothing, walls included; 1e-9 allows for rounding).
  for (const auto& g : p.grains) {
    CHECK(g.shape == core::ShapeKind::Sphere);
    CHECK(g.position.x() >= 0.0);
    CHECK(g.position.x() < 6.0);
    CHECK(g.position.y() - 0.5 * g.size >= -1e-9);
    CHECK(g.position.y() + 0.5 * g.size <= 4.0 + 1e-9);
    CHECK(g.position.z() - 0.5 * g.size >= -1e-9);
  }

  // config.json is the resolved configuration: the flags given, the defaults for the rest.
  const core::RunConfig cfg = json::parse(slurp(dir / "config.json")).get<core::RunConfig>();
  CHECK(cfg.box.lengthX == 6.0);
  CHECK(cfg.box.width == 4.0);
  CHECK(cfg.box.height == 4.0);
  CHECK(cfg.box.wallFriction == 0.3);
  CHECK(cfg.seed == 3);
  CHECK(cfg.backend == "nscd");
  CHECK(cfg.population.smallFraction == core::PopulationDef{}.smallFraction);

  CHECK(fs::exists(dir / "vtk" / "deposit_grains.pvd"));
  CHECK(fs::exists(dir / "vtk" / "deposit_grains_000000.vtp"));
  // No staging directory left next to the output.
  for (const auto& e : fs::directory_iterator(s.dir / "a")) CHECK(e.path().filename() == "dep");

  // Same seed, same pile, bit for bit; --quiet silences stderr; an existing --out is refreshed.
  const Result again = s.run("deposit --length-x 6 --width 4 --height 4 --seed 3 --wall-friction 0.3 --quiet --out b");
  REQUIRE(again.code == 0);
  CHECK(again.err.empty());
  CHECK(slurp(s.dir / "b" / "packing.json") == slurp(dir / "packing.json"));
  const Result other = s.run("deposit --length-x 6 --width 4 --height 4 --seed 4 --wall-friction 0.3 -q --out b");
  REQUIRE(other.code == 0);
  CHECK(slurp(s.dir / "b" / "packing.json") != slurp(dir / "packing.json"));
  CHECK(core::readPacking(s.dir / "b" / "packing.json").grains.size() > 10);
}

TEST_CASE("the run configuration round-trips through JSON") {
  core::RunConfig c;
  c.box.lengthX = 7.25;
  c.box.width = 1.0 / 3.0;
  c.box.periodicY = true;
  c.box.wallFriction = 0.5;
  c.population.shape = core::ShapeKind::Pinacoid;
  c.population.smallFraction = 40.0;
  c.population.pinacoid.alphaDeg = 55.5;
  c.deposition.expectedSolidFraction = 0.58;
  c.compaction.dt = 3.3e-4;
  c.compaction.adaptiveDt = true;
  c.compaction.timeLimit = 123.0;
  c.compaction.checkInterval = 77;
  c.compaction.frameInterval = 5;
  c.compaction.protocol = core::Protocol::QuasiStatic;
  c.compaction.trustRadius = 0.02;
  c.compaction.forceRatio = 2e-4;
  c.backend = "bullet";
  c.backendOptions = {{"iterations", 50}};
  c.seed = 18446744073709551615ULL;  // the largest seed survives (JSON unsigned, not a double)
  c.threads = 2;
  const json j = c;
  const core::RunConfig d = j.get<core::RunConfig>();
  CHECK(json(d) == j);
  CHECK(d.seed == c.seed);
  CHECK(d.box.width == c.box.width);
  CHECK(d.population.shape == core::ShapeKind::Pinacoid);
  CHECK(d.compaction.dt == c.compaction.dt);
  CHECK(d.compaction.checkInterval == 77);
  CHECK(d.compaction.adaptiveDt);
  CHECK(d.compaction.protocol == core::Protocol::QuasiStatic);
  CHECK(j.at("compaction").at("protocol") == "quasi-static");
  CHECK(d.compaction.trustRadius == 0.02);
  CHECK_NOTHROW(d.validate());
  // snake_case keys, as in the packing file.
  for (const char* k :
       {"box", "population", "deposition", "compaction", "backend", "backend_options", "seed", "threads"})
    CHECK(j.contains(k));
  for (const char* k :
       {"dt", "adaptive_dt", "time_limit", "check_interval", "frame_interval", "force_ratio", "moment_ratio",
        "kinetic_ratio", "protocol", "switch_kinetic_ratio", "trust_radius", "settle_tolerance", "finisher_max_step",
        "finisher_max_steps"})
    CHECK(j.at("compaction").contains(k));
  // A partial document takes the defaults for the rest (sweeps override a base this way).
  const auto partial = json::parse(R"({"box": {"width": 5}, "seed": 9})").get<core::RunConfig>();
  CHECK(partial.box.width == 5.0);
  CHECK(partial.seed == 9);
  CHECK(partial.backend == "nscd");
  CHECK(partial.compaction.timeLimit == core::CompactionDef{}.timeLimit);
}

TEST_CASE("the run configuration refuses bad values naming the field") {
  auto refused = [](auto edit, const std::string& field) {
    core::RunConfig c;
    edit(c);
    INFO(field);
    CHECK_THROWS_WITH(c.validate(), Catch::Contains(field));
  };
  refused([](core::RunConfig& c) { c.backend = "foo"; }, "backend");
  refused([](core::RunConfig& c) { c.threads = 0; }, "threads");
  refused([](core::RunConfig& c) { c.box.width = -1; }, "width");
  refused([](core::RunConfig& c) { c.population.smallFraction = 101; }, "small fraction");
  refused([](core::RunConfig& c) { c.compaction.timeLimit = 0; }, "compaction.time_limit");
  refused([](core::RunConfig& c) { c.compaction.dt = -1e-3; }, "compaction.dt");
  refused([](core::RunConfig& c) { c.compaction.checkInterval = 0; }, "compaction.check_interval");
  refused([](core::RunConfig& c) { c.compaction.kineticRatio = -1; }, "compaction.kinetic_ratio");
  refused([](core::RunConfig& c) { c.compaction.switchKineticRatio = 0; }, "compaction.switch_kinetic_ratio");
  refused([](core::RunConfig& c) { c.compaction.trustRadius = 0; }, "compaction.trust_radius");
  refused([](core::RunConfig& c) { c.compaction.trustRadius = 0.9; }, "compaction.trust_radius");
  refused([](core::RunConfig& c) { c.compaction.settleTolerance = -1e-6; }, "compaction.settle_tolerance");
  refused([](core::RunConfig& c) { c.compaction.finisherMaxStep = 0; }, "compaction.finisher_max_step");
  refused([](core::RunConfig& c) { c.compaction.finisherMaxSteps = 0; }, "compaction.finisher_max_steps");
  CHECK_THROWS_WITH(json::parse(R"({"compaction": {"protocol": "static"}})").get<core::RunConfig>(),
                    Catch::Contains("compaction.protocol: unknown protocol 'static'"));
  refused([](core::RunConfig& c) { c.deposition.expectedSolidFraction = 1.2; }, "expected solid fraction");
  refused([](core::RunConfig& c) { c.backendOptions = json::array(); }, "backend_options");
  CHECK_THROWS_WITH(json::parse(R"({"sed": 3})").get<core::RunConfig>(), Catch::Contains("config.sed: unknown key"));
  CHECK_THROWS_WITH(json::parse(R"({"seed": -3})").get<core::RunConfig>(), Catch::Contains("config.seed"));
  CHECK_THROWS_WITH(json::parse(R"({"threads": "two"})").get<core::RunConfig>(), Catch::Contains("config.threads"));
  CHECK_THROWS_WITH(json::parse(R"({"compaction": {"adaptive_dt": "yes"}})").get<core::RunConfig>(),
                    Catch::Contains("compaction.adaptive_dt"));
  CHECK_THROWS_WITH(json::parse(R"({"compaction": {"time_limt": 3}})").get<core::RunConfig>(),
                    Catch::Contains("compaction.time_limt: unknown key"));
  // core keeps its own list of backend names (it cannot see backends/): it must match the factory.
  for (auto name : backends::backendNames()) {
    core::RunConfig c;
    c.backend = std::string(name);
    CHECK_NOTHROW(c.validate());
  }
}
