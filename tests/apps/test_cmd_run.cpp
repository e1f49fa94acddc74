// `confpack run` (apps/cmd_run.cpp) end to end: --from takes the grains of a packing file to rest;
// --config reruns a run from its config.json; SIGTERM stops a run cleanly.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/packing_io.hpp"
#include "core/run_config.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::ConfpackSession;
namespace fs = std::filesystem;

namespace {

/// Three unit spheres stacked above one point, apart, between two frictionless side walls.
core::Packing looseColumn() {
  core::Packing p;
  p.box.lengthX = 3.0;
  p.box.width = 3.0;
  p.box.height = 6.0;
  for (double z : {1.5, 3.5, 5.0}) p.grains.push_back(testing::sphere(1.0, core::Vec3(1.5, 1.5, z)));
  return p;
}

/// SIGTERM to a running `confpack run` (started with its stderr to `err`): it must exit with 143
/// and one line on stderr, which is returned (and `err` removed).
std::string stopWithSigterm(pid_t pid, const fs::path& err) {
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  const std::string message = testing::slurp(err);
  fs::remove(err);
  INFO(message);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 143);
  CHECK(testing::lineCount(message) == 1);
  return message;
}

}  // namespace

TEST_CASE("run --from brings a packing's grains to rest: a bead column carries k m g at its k-th contact") {
  ConfpackSession s("cmd_run_from");
  core::writePacking(looseColumn(), s.dir / "column.json");
  const auto r = s.run("run --from column.json --protocol quasi-static --time-limit 20 --out out -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json result = nlohmann::json::parse(testing::slurp(s.dir / "out" / "result.json"));
  CHECK(result["equilibrium"]["reached"].get<bool>());
  CHECK(result["n_grains"].get<int>() == 3);
  CHECK(result["deposit"]["from"].get<std::string>() == "column.json");
  CHECK(result["config"]["box"]["width"].get<double>() == 3.0);
  // The result records the build that computed it, as `confpack --version` names it.
  const auto version = s.run("--version");
  CHECK(version.code == 0);
  CHECK(version.out == "confpack " + result["confpack_version"].get<std::string>() + " (revision " +
                           result["confpack_revision"].get<std::string>() + ")\n");

  // Centres at d/2, 3d/2, 5d/2 above the floor, and the contact under the k-th bead from the top
  // carries the weight of k beads, m = pi/6 (rho = g = d = 1).
  const core::Packing end = core::readPacking(s.dir / "out" / "packing.json");
  std::vector<double> z;
  for (const core::Grain& g : end.grains) z.push_back(g.position.z());
  std::sort(z.begin(), z.end());
  for (int k = 0; k < 3; ++k) CHECK(z[k] == Approx(0.5 + k).margin(1e-6));
  REQUIRE(end.contacts.has_value());
  std::vector<double> loads;
  for (const core::Contact& c : *end.contacts) {
    double f = 0.0;
    for (const core::ContactPoint& p : c.points) f += p.normalForce;
    if (f > 1e-9) loads.push_back(f);
  }
  std::sort(loads.begin(), loads.end());
  const double m = M_PI / 6.0;
  REQUIRE(loads.size() == 3);
  for (int k = 0; k < 3; ++k) CHECK(loads[k] == Approx((k + 1) * m).epsilon(1e-6));
}

TEST_CASE("run --from takes a pinacoid pile where a ridge lies 0.3 degrees off a face to rest") {
  // The last state of the shape study's pile that never came to rest (E/L = 0.5, alpha = 60,
  // seed 1; docs/pinacoid-shape.md): 338 pinacoids, two of which meet with a ridge 0.3 degrees
  // off a face. With one point for that pair the finisher is not at rest after these 300 steps
  // (force ratio 5.9e-3); with every point within reach it is at rest in 43 (contact_region.hpp).
  ConfpackSession s("cmd_run_ridge");
  const fs::path pile = fs::path(CONFPACK_SOURCE_DIR) / "tests" / "data" / "pinacoid-pile-ridge-off-face.json";
  const auto r = s.run("run --from '" + pile.string() +
                       "' --protocol quasi-static --fall-time-limit 0.001 --time-limit 1"
                       " --compaction-options '{\"finisher_max_steps\": 300}' --out out -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json result = nlohmann::json::parse(testing::slurp(s.dir / "out" / "result.json"));
  CHECK(result["n_grains"].get<int>() == 338);
  CHECK(result["equilibrium"]["reached"].get<bool>());
  CHECK(result["equilibrium"]["max_force_ratio"].get<double>() < 1e-4);
  CHECK(result["interpenetration_percent"]["exact"].get<double>() < 1e-10);
}

TEST_CASE("run --from refuses box options and unreadable files with one line, exit 2 and no output") {
  ConfpackSession s("cmd_run_from_bad");
  core::writePacking(looseColumn(), s.dir / "column.json");
  const auto widthToo = s.run("run --from column.json --width 5 --out out");
  CHECK(widthToo.code == 2);
  CHECK(widthToo.err.find("drop --width") != std::string::npos);
  CHECK(testing::lineCount(widthToo.err) == 1);
  const auto missing = s.run("run --from missing.json --out out");
  CHECK(missing.code == 2);
  CHECK(missing.err.find("missing.json") != std::string::npos);
  CHECK(testing::lineCount(missing.err) == 1);
  CHECK(!fs::exists(s.dir / "out"));
}

TEST_CASE("run refuses a run whose analysis would exceed max_cells before depositing: one line, exit 2, no output") {
  ConfpackSession s("cmd_run_max_cells");
  // ~6.9e4 grains (below max_grains) x 1e6 phi(y) slices of 0.02 d_L across a 20,000 d_L width:
  // refused at once, where the deposit and the compaction would take hours before the analysis.
  const auto start = std::chrono::steady_clock::now();
  const auto wide = s.run("run --length-x 2 --width 20000 --height 1.5 --out out");
  CHECK(wide.code == 2);
  CHECK_THAT(wide.err, Catch::Contains("grains x phi(y) slices of 0.02 d_L), more than max_cells (2e+08)"));
  CHECK(testing::lineCount(wide.err) == 1);
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(20));
  CHECK(!fs::exists(s.dir / "out"));
}

TEST_CASE("run --compaction-options sets compaction keys (over the flags) and refuses bad ones by name") {
  ConfpackSession s("cmd_run_compaction_options");
  core::writePacking(looseColumn(), s.dir / "column.json");
  // The finisher bounded at 2 steps from the bead column's loose start: not at rest, as asked.
  const auto r = s.run(
      "run --from column.json --protocol quasi-static --time-limit 20 --out out -q "
      "--compaction-options '{\"time_limit\": 0.05, \"finisher_max_steps\": 2, \"trust_radius\": 0.02}'");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json result = nlohmann::json::parse(testing::slurp(s.dir / "out" / "result.json"));
  CHECK(result["config"]["compaction"]["time_limit"].get<double>() == 0.05);
  CHECK(result["config"]["compaction"]["trust_radius"].get<double>() == 0.02);
  CHECK_FALSE(result["equilibrium"]["reached"].get<bool>());
  CHECK(result["timing"]["stages"]["quasi_static"]["steps"].get<long>() == 2);

  for (const auto& [options, named] :
       std::vector<std::pair<std::string, std::string>>{{"{\"trust_radius\": 0.9}", "compaction.trust_radius"},
                                                        {"{\"no_such_key\": 1}", "no_such_key"},
                                                        {"{not json", "--compaction-options"}}) {
    const auto bad = s.run("run --from column.json --out bad --compaction-options '" + options + "'");
    INFO(bad.err);
    CHECK(bad.code == 2);
    CHECK(bad.err.find(named) != std::string::npos);
    CHECK(testing::lineCount(bad.err) == 1);
  }
  CHECK(!fs::exists(s.dir / "bad"));
}

TEST_CASE("run --config DIR/config.json reruns the run: the same configuration read back, the same packing bits") {
  ConfpackSession s("cmd_run_config");
  for (const std::string backend : {"nscd", "bullet"}) {
    INFO(backend);
    const std::string option = backend == "nscd" ? R"('{"tolerance": 1e-8}')" : R"('{"iterations": 50}')";
    const auto first = s.run("run --length-x 3 --width 3 --height 3 --time-limit 2 --wall-friction 0.3 --seed 5 -q " +
                             ("--backend-options " + option + " --backend " + backend + " --out " + backend));
    INFO(first.err);
    REQUIRE(first.code == 0);
    // What the run wrote is a configuration the reader takes: the flags given, the time step taken
    // and the backend's resolved settings (every key) as its options.
    const nlohmann::json written = nlohmann::json::parse(testing::slurp(s.dir / backend / "config.json"));
    const nlohmann::json result = nlohmann::json::parse(testing::slurp(s.dir / backend / "result.json"));
    const core::RunConfig cfg = written.get<core::RunConfig>();
    CHECK(nlohmann::json(cfg) == written);
    CHECK(cfg.backend == backend);
    CHECK(cfg.seed == 5);
    CHECK(cfg.walls.friction == 0.3);
    CHECK(cfg.compaction.timeLimit == 2.0);
    CHECK(cfg.compaction.dt == result["config"]["compaction"]["dt"].get<double>());
    CHECK(cfg.compaction.dt > 0.0);
    CHECK(cfg.backendOptions == result["config"]["backend_settings"]);
    CHECK(cfg.backendOptions.size() > 5);
    CHECK(cfg.backendOptions.contains(backend == "nscd" ? "tolerance" : "iterations"));

    const auto again = s.run("run --config " + backend + "/config.json -q --out " + backend + "_again");
    INFO(again.err);
    REQUIRE(again.code == 0);
    for (const char* file : {"config.json", "packing.json", "phi_y.csv"})
      CHECK(testing::slurp(s.dir / (backend + "_again") / file) == testing::slurp(s.dir / backend / file));
  }
  // The file holds the whole configuration: a flag that sets part of it is refused, as is a bad file,
  // by name, before any work.
  const auto seed = s.run("run --config nscd/config.json --seed 2 --out x");
  CHECK(seed.code == 2);
  CHECK(seed.err ==
        "confpack run: error: --config gives the whole configuration; drop --seed (or change it in the file)\n");
  // (A small box: were the typo taken, the run would end in a second, not run the default box.)
  std::ofstream(s.dir / "typo.json") << R"({"box": {"widht": 3, "length_x": 3, "height": 3},
                                            "compaction": {"time_limit": 1}})";
  const auto typo = s.run("run --config typo.json --out x");
  CHECK(typo.code == 2);
  CHECK(testing::lineCount(typo.err) == 1);
  CHECK(typo.err.find("confpack run: error: typo.json: box.widht: unknown key") == 0);
  CHECK(!fs::exists(s.dir / "x"));
}

TEST_CASE("SIGTERM stops a run at its next step: one line saying where, exit 143, nothing written") {
  ConfpackSession s("cmd_run_sigterm");
  const fs::path err = s.dir.string() + ".err";
  // A compaction of about 1,000 spheres for 400 t0: minutes of work, stopped after a second.
  const pid_t pid = testing::startConfpack(
      s.dir, {"run", "--length-x", "10", "--width", "10", "--height", "10", "--out", "out", "-q"}, err);
  REQUIRE(pid >= 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const std::string message = stopWithSigterm(pid, err);
  INFO(message);
  CHECK(message.find("confpack run: error: interrupted by SIGTERM") != std::string::npos);
  CHECK(s.empty());  // neither out/ nor its staging folder
}

// docs/model.md, "Checkpoints": a run given --checkpoint saves its state when SIGTERM stops it (a
// cluster's time limit) and the same command goes on from there, to the same bits as a run never
// stopped (nscd).
TEST_CASE("run --checkpoint: stopped by SIGTERM, the same command resumes it and ends on the same packing") {
  ConfpackSession s("cmd_run_checkpoint");
  const std::vector<std::string> args = {"run",           "--length-x",   "6",  "--width", "6", "--height", "8",
                                         "--adaptive-dt", "--time-limit", "60", "-q"};
  const auto whole = s.run("run --length-x 6 --width 6 --height 8 --adaptive-dt --time-limit 60 -q --out whole");
  REQUIRE(whole.code == 0);

  const fs::path err = s.dir.string() + ".err";
  std::vector<std::string> stopped = args;
  for (const char* a : {"--out", "out", "--checkpoint", "state/run.json", "--checkpoint-every", "0.001"})
    stopped.push_back(a);
  const pid_t pid = testing::startConfpack(s.dir, stopped, err);
  REQUIRE(pid >= 0);
  // Stopped once it has saved a state (at every check, with --checkpoint-every 0.001).
  const fs::path state = s.dir / "state" / "run.json";
  for (int k = 0; k < 2000 && !fs::exists(state); ++k) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const std::string message = stopWithSigterm(pid, err);
  INFO(message);
  CHECK(message.find("its state is saved in state/run.json; the same command resumes it") != std::string::npos);
  REQUIRE(fs::exists(state));
  CHECK(!fs::exists(s.dir / "out"));

  const auto resumed = s.run(
      "run --length-x 6 --width 6 --height 8 --adaptive-dt --time-limit 60 -q --out out "
      "--checkpoint state/run.json");
  INFO(resumed.err);
  REQUIRE(resumed.code == 0);
  CHECK(testing::slurp(s.dir / "out" / "packing.json") == testing::slurp(s.dir / "whole" / "packing.json"));
  const nlohmann::json result = nlohmann::json::parse(testing::slurp(s.dir / "out" / "result.json"));
  CHECK(result["timing"]["checkpoint"]["resumes"] == 1);
  CHECK(!fs::exists(state));  // removed once the run is done
}
