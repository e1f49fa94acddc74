// compaction/checkpoint.hpp: a compaction stopped and resumed from its checkpoint. nscd saves
// everything its next step reads, so the resumed run takes the same steps, bit for bit, as the run
// never stopped, in the fall and in the finisher; Bullet takes back poses and velocities only.
// The stop here is a dead process (the progress callback throws at a check, as a kill -9 would
// end the run between two saves); SIGTERM's own save is tested through the CLI
// (tests/apps/test_cmd_run.cpp).
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "compaction/checkpoint.hpp"
#include "compaction/compaction.hpp"
#include "compaction/deposition.hpp"
#include "core/run_config.hpp"
#include "tests/support/scratch.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
namespace fs = std::filesystem;

namespace {

core::RunConfig smallPile(const std::string& backend, core::ShapeKind shape) {
  core::RunConfig cfg = testing::smallQuasiStaticRun(backend, 0.3);  // friction rows are warm-started too
  cfg.population.shape = shape;
  return cfg;
}

struct Killed : std::runtime_error {
  Killed() : std::runtime_error("killed") {}
};

/// The compaction with a checkpoint saved at every check, killed at the `killAt`-th check.
void killedAt(const core::RunConfig& cfg, const compaction::Deposit& dep, const fs::path& file, int killAt) {
  compaction::Checkpointing every;
  every.file = file;
  every.everySeconds = 0.0;
  int checks = 0;
  CHECK_THROWS_AS(compaction::compact(
                      cfg, dep, {},
                      [&](double, const std::string&) {
                        if (++checks == killAt) throw Killed();
                      },
                      every),
                  Killed);
}

/// A run of `cfg` from its deposit, whole, and again stopped at its `killAt`-th check with a
/// checkpoint saved at every check, in a scratch folder named `name`.
struct WholeAndStopped {
  compaction::Deposit dep;
  compaction::CompactionOutcome whole;
  testing::ScratchDir scratch;
  fs::path file;
  WholeAndStopped(const core::RunConfig& cfg, const std::string& name, int killAt)
      : dep(compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed)),
        whole(compaction::compact(cfg, dep)),
        scratch(name),
        file(scratch.path() / "run.json") {
    killedAt(cfg, dep, file, killAt);
  }
};

nlohmann::json readJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

void checkSamePacking(const compaction::CompactionOutcome& a, const compaction::CompactionOutcome& b) {
  REQUIRE(a.packing.grains.size() == b.packing.grains.size());
  for (std::size_t i = 0; i < a.packing.grains.size(); ++i) {
    INFO("grain " << i);
    REQUIRE(a.packing.grains[i].position == b.packing.grains[i].position);  // the same bits
    REQUIRE(a.packing.grains[i].orientation.coeffs() == b.packing.grains[i].orientation.coeffs());
  }
  CHECK(a.timing["steps"] == b.timing["steps"]);
  CHECK(a.timing["iterations"] == b.timing["iterations"]);
  CHECK(a.reached == b.reached);
  CHECK(a.history.size() == b.history.size());
}

}  // namespace

TEST_CASE("checkpoint: an nscd run resumed in its fall or in its finisher ends on the same bits") {
  const core::ShapeKind shape = GENERATE(core::ShapeKind::Sphere, core::ShapeKind::Pinacoid);
  const bool inFinisher = GENERATE(false, true);
  const bool pinacoids = shape == core::ShapeKind::Pinacoid;
  INFO("pinacoids " << pinacoids << ", killed in the " << (inFinisher ? "finisher" : "fall"));
  core::RunConfig cfg = smallPile("nscd", shape);
  if (pinacoids) cfg.box.height = 3.0;
  // Handed over at the first check after the fall has begun, so that the finisher has steps to
  // spare; bounded, since the same bits, not rest, are what is tested.
  if (inFinisher) cfg.compaction.switchKineticRatio = 1.0;
  cfg.compaction.finisherMaxSteps = 100;
  cfg.compaction.fallTimeLimit = 6.0;
  const compaction::Deposit dep = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  const compaction::CompactionOutcome whole = compaction::compact(cfg, dep);
  const auto& stages = whole.timing["stages"];
  INFO(stages.dump());
  REQUIRE(stages.contains("quasi_static"));
  // Checks of the fall come every 50 steps; the finisher's every 20 of its steps.
  const long fallChecks = (stages["dynamic"]["steps"].get<long>() + 49) / 50;
  REQUIRE(stages["quasi_static"]["steps"].get<long>() >= 60);
  REQUIRE(fallChecks >= 4);

  const testing::ScratchDir scratch("checkpoint_nscd");
  const fs::path file = scratch.path() / "run.json";
  // Killed at a check: the checkpoint is the one saved at the check before.
  killedAt(cfg, dep, file, inFinisher ? static_cast<int>(fallChecks + 2) : 3);
  REQUIRE(fs::exists(file));
  CHECK(readJson(file)["stage"] == (inFinisher ? "finisher" : "fall"));
  compaction::Checkpointing resume;
  resume.file = file;
  const compaction::CompactionOutcome resumed = compaction::compact(cfg, dep, {}, {}, resume);
  checkSamePacking(whole, resumed);
  CHECK(resumed.timing["checkpoint"]["resumes"] == 1);
  CHECK(resumed.timing["checkpoint"]["exact"] == true);
  if (inFinisher) {  // a finisher state that cannot be: set aside, the run starts afresh
    nlohmann::json j = readJson(file);
    j["finisher"]["h"] = -1.0;
    std::ofstream(file) << j.dump();
    const compaction::CompactionOutcome afresh = compaction::compact(cfg, dep, {}, {}, resume);
    CHECK(afresh.timing["checkpoint"]["resumes"] == 0);
    CHECK_THAT(afresh.timing["checkpoint"]["ignored"].get<std::string>(), Catch::Contains("does not fit"));
    checkSamePacking(whole, afresh);
  }
}

TEST_CASE("checkpoint: an nscd run on the \"switching\" preconditioner resumed in its fall ends on the same bits") {
  // A budget of one sgs iteration: the solves switch to "cholesky", and the state that decides
  // the next solve's preconditioner (on "cholesky", solves since) is in the checkpoint.
  core::RunConfig cfg = smallPile("nscd", core::ShapeKind::Sphere);
  cfg.backendOptions = {{"preconditioner", "switching"}, {"preconditioner_switch", 1e-4}};
  cfg.compaction.finisherMaxSteps = 20;
  cfg.compaction.fallTimeLimit = 4.0;
  const WholeAndStopped run(cfg, "checkpoint_switching", 4);
  REQUIRE(fs::exists(run.file));
  const nlohmann::json saved = readJson(run.file)["backend"]["preconditioner_switch"];
  INFO(saved.dump());
  CHECK(saved["on_cholesky"] == true);
  CHECK(saved["solves"].get<int>() > 0);
  compaction::Checkpointing resume;
  resume.file = run.file;
  checkSamePacking(run.whole, compaction::compact(cfg, run.dep, {}, {}, resume));
}

TEST_CASE("checkpoint: Bullet resumes from the saved poses and velocities and still runs its time") {
  core::RunConfig cfg = smallPile("bullet", core::ShapeKind::Sphere);
  cfg.compaction.timeLimit = 3.0;
  const WholeAndStopped run(cfg, "checkpoint_bullet", 4);
  const compaction::CompactionOutcome& whole = run.whole;
  const nlohmann::json saved = readJson(run.file);
  const long savedSteps = saved["steps"].get<long>();
  compaction::Checkpointing resume;
  resume.file = run.file;
  const compaction::CompactionOutcome resumed = compaction::compact(cfg, run.dep, {}, {}, resume);
  CHECK(resumed.timing["checkpoint"]["exact"] == false);
  CHECK(resumed.timing["checkpoint"]["resumes"] == 1);
  // The same step count to the same time limit, the history of the first attempt kept.
  CHECK(resumed.timing["steps"] == whole.timing["steps"]);
  CHECK(resumed.history.size() == whole.history.size());
  CHECK(resumed.history.front().steps == whole.history.front().steps);
  CHECK(savedSteps == 4 * 50 - 50);  // saved at the third check, killed at the fourth
  // The contacts are solved cold once: the pile ends close to, not on, the uninterrupted one's.
  double farthest = 0.0;
  for (std::size_t i = 0; i < whole.packing.grains.size(); ++i)
    farthest = std::max(farthest, (whole.packing.grains[i].position - resumed.packing.grains[i].position).norm());
  CHECK(farthest < 0.5);
}

TEST_CASE("checkpoint: another run's checkpoint, or a damaged one, is set aside and the run starts afresh") {
  core::RunConfig cfg = smallPile("nscd", core::ShapeKind::Sphere);
  cfg.compaction.timeLimit = 2.0;
  cfg.compaction.protocol = core::Protocol::Dynamic;
  const compaction::Deposit dep = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  const compaction::CompactionOutcome whole = compaction::compact(cfg, dep);
  const testing::ScratchDir scratch("checkpoint_other");
  const fs::path file = scratch.path() / "run.json";
  killedAt(cfg, dep, file, 2);
  compaction::Checkpointing resume;
  resume.file = file;

  SECTION("another seed's") {
    core::RunConfig other = cfg;
    other.seed = 3;
    const compaction::Deposit otherDep = compaction::deposit(other.box, other.population, other.deposition, other.seed);
    const compaction::CompactionOutcome out = compaction::compact(other, otherDep, {}, {}, resume);
    CHECK(out.timing["checkpoint"]["resumes"] == 0);
    CHECK(out.timing["checkpoint"]["ignored"].get<std::string>().find("another run's") != std::string::npos);
  }
  SECTION("the same run's with another thread count: resumed, the same bits") {
    core::RunConfig two = cfg;
    two.threads = 2;
    const compaction::CompactionOutcome out = compaction::compact(two, dep, {}, {}, resume);
    CHECK(out.timing["checkpoint"]["resumes"] == 1);
    checkSamePacking(whole, out);
  }
  SECTION("a damaged file") {
    nlohmann::json j = readJson(file);
    j["backend"]["cache"]["entries"] = 7;
    std::ofstream(file) << j.dump();
    const compaction::CompactionOutcome out = compaction::compact(cfg, dep, {}, {}, resume);
    CHECK(out.timing["checkpoint"]["resumes"] == 0);
    CHECK(out.timing["checkpoint"]["ignored"].get<std::string>().find("does not fit") != std::string::npos);
    checkSamePacking(whole, out);
  }
}

TEST_CASE("checkpoint: its description says the stage and how far from rest its last measured check was") {
  core::RunConfig cfg = smallPile("nscd", core::ShapeKind::Sphere);
  cfg.compaction.protocol = core::Protocol::Dynamic;
  cfg.compaction.timeLimit = 6.0;
  const compaction::Deposit dep = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  const testing::ScratchDir scratch("checkpoint_describe");
  const fs::path file = scratch.path() / "run.json";
  killedAt(cfg, dep, file, 8);
  nlohmann::json j = readJson(file);
  // The last check with ratios measured: [steps, time, wall, force, moment, kinetic, ...].
  nlohmann::json last;
  for (const nlohmann::json& e : j["history"])
    if (e[3].is_number() && e[5].is_number()) last = e;
  REQUIRE(!last.is_null());
  const std::string said = compaction::describeCheckpoint(file);
  CHECK_THAT(said, Catch::StartsWith(fmt::format("checkpoint: fall at t = {:.1f}, ", j["sim_time"].get<double>())));
  CHECK_THAT(said, Catch::EndsWith(fmt::format("; last check: force ratio {:.2g} (rest below 0.0001), kinetic ratio "
                                               "{:.2g} (below 1e-08)",
                                               last[3].get<double>(), last[5].get<double>())));

  // A fall whose checks have measured nothing yet (no contacts): no ratios to tell.
  for (nlohmann::json& e : j["history"]) e[3] = "inf";
  std::ofstream(file) << j.dump();
  CHECK(compaction::describeCheckpoint(file).find("last check") == std::string::npos);
  // Nothing to say of a missing or unreadable file.
  std::ofstream(file) << "{";
  CHECK(compaction::describeCheckpoint(file).empty());
  CHECK(compaction::describeCheckpoint(file.parent_path() / "none.json").empty());
}
