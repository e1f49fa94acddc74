// study/run_pipeline.hpp: a run from a packing records its settle (docs/model.md, "Settling a pile
// from another backend"): how far the grains moved to rest, and phi and Z before and after.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "analysis/coordination.hpp"
#include "analysis/rigidity.hpp"
#include "compaction/compaction.hpp"
#include "core/json_input.hpp"
#include "study/run_pipeline.hpp"
#include "study/sweep_runner.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;

namespace {

/// The run of `cfg` started from `packing`'s grains, as `confpack run --from` starts it.
study::FinishedRun settle(const core::RunConfig& cfg, const core::Packing& packing) {
  const compaction::Deposit from = compaction::depositFromPacking(packing, "pile.json");
  return study::runProtocol(cfg, {}, {}, &from);
}

}  // namespace

TEST_CASE("settle: a pile already at rest moves by nothing and keeps its phi and Z") {
  core::RunConfig cfg = testing::smallQuasiStaticRun("nscd", 0.0);
  cfg.box.height = 9.0;  // a bulk region 3 d_L from the floor and from the free surface
  const study::FinishedRun rest = study::runProtocol(cfg);
  REQUIRE(rest.result["equilibrium"]["reached"].get<bool>());
  CHECK_FALSE(rest.result.contains("settle"));  // a run from a deposit has nothing to record
  // The relaxation history's last check is the final state: its phi and Z are the analysis's.
  const nlohmann::json& last = rest.result["timing"]["history"].back();
  CHECK(last["solid_fraction"].get<double>() == Approx(rest.result["solid_fraction"].get<double>()).epsilon(1e-12));
  CHECK(last["Z"].get<double>() == Approx(rest.result["coordination"]["Z"].get<double>()).epsilon(1e-12));

  const study::FinishedRun again = settle(cfg, rest.packing);
  REQUIRE(again.result.contains("settle"));
  const nlohmann::json& s = again.result["settle"];
  INFO(s.dump());
  CHECK(s["from"] == "pile.json");
  CHECK(s["reached"].get<bool>());
  // Rigid grains in equilibrium: the contact forces hold gravity from the first step, and no grain
  // moves by more than the solver's tolerance allows (a millionth of a grain over the run).
  CHECK(s["max_displacement"].get<double>() < 1e-6);
  CHECK(s["mean_displacement"].get<double>() <= s["max_displacement"].get<double>());
  CHECK(s["after"]["solid_fraction"].get<double>() ==
        Approx(s["before"]["solid_fraction"].get<double>()).epsilon(1e-9));
  CHECK(s["after"]["Z"].get<double>() == Approx(s["before"]["Z"].get<double>()).margin(1e-9));
}

TEST_CASE("settle: a Bullet pile of frictionless spheres stopped early, brought to rest by nscd, is isostatic") {
  // A biperiodic pile of a few hundred spheres, tall enough for a bulk region 3 d_L from the floor
  // and from the free surface; Bullet stops it at 8 t0, still moving (force ratio of order one).
  core::RunConfig bullet;
  bullet.box.lengthX = 6.0;
  bullet.box.width = 6.0;
  bullet.box.periodicY = true;
  bullet.box.height = 10.0;
  bullet.seed = 1;
  bullet.backend = "bullet";
  bullet.compaction.timeLimit = 8.0;
  const study::FinishedRun stopped = study::runProtocol(bullet);
  REQUIRE(stopped.packing.grains.size() > 300);
  CHECK_FALSE(stopped.result["equilibrium"]["reached"].get<bool>());

  core::RunConfig nscd = bullet;
  nscd.backend = "nscd";
  nscd.compaction.protocol = core::Protocol::QuasiStatic;
  nscd.compaction.timeLimit = 40.0;
  const study::FinishedRun settled = settle(nscd, stopped.packing);
  const nlohmann::json& s = settled.result["settle"];
  INFO(s.dump());
  REQUIRE(s["reached"].get<bool>());
  // The settle moved the grains (Bullet's pile was not at rest), by a fraction of a grain.
  CHECK(s["mean_displacement"].get<double>() > 1e-4);
  CHECK(s["max_displacement"].get<double>() < 1.0);
  // Rigid frictionless spheres at rest: an isostatic network, no self-stress (Roux, PRE 61, 6802,
  // 2000), and the coordination of nscd's own pile from the same deposit at rest within 2 % (the
  // same bulk region counts boundary contacts alike in both).
  const auto rigidity = analysis::contactRigidity(
      settled.packing, analysis::forceCarryingContacts(settled.packing, *settled.packing.contacts, false));
  REQUIRE(rigidity.has_value());
  CHECK(rigidity->selfStresses() == 0);
  const study::FinishedRun own = study::runProtocol(nscd);
  REQUIRE(own.result["equilibrium"]["reached"].get<bool>());
  const double zOwn =
      own.result["coordination"]["Z"].get<double>() + 2.0 * own.result["coordination"]["wall"].get<double>();
  const double zSettled = s["after"]["Z"].get<double>() + 2.0 * s["after"]["wall"].get<double>();
  CHECK(zSettled == Approx(zOwn).epsilon(0.02));
  // Bullet's own count, as it stopped, is not: its impulses are not converged forces.
  CHECK(s["before"]["Z"].get<double>() < s["after"]["Z"].get<double>());
}

TEST_CASE("settleAndWrite: a sweep's settle_with takes a finished Bullet run on to rest beside it, in RUN/settled/") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_settle_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  core::RunConfig cfg = testing::smallQuasiStaticRun("bullet", 0.0);
  cfg.compaction.timeLimit = 2.0;  // stopped early, still falling
  cfg.backendOptions = {{"iterations", 20}};
  const nlohmann::json stopped = study::runAndWrite(cfg, dir);
  CHECK_FALSE(stopped["equilibrium"]["reached"].get<bool>());

  const nlohmann::json settled = study::settleAndWrite(cfg, dir, "nscd");
  const fs::path out = dir / study::kSettledFolder;
  CHECK(fs::exists(out / "result.json"));
  CHECK(fs::exists(out / "packing.json"));
  const nlohmann::json config = core::readJsonFile(out / "config.json", "config");
  // The run's box and grains, nscd with its own default options and the quasi-static protocol.
  CHECK(config["backend"] == "nscd");
  CHECK(config["backend_options"].empty());
  CHECK(config["compaction"]["protocol"] == "quasi-static");
  CHECK(config["box"] == nlohmann::json(cfg.box));
  CHECK(settled["settle"]["from"] == "../packing.json");
  CHECK(settled["equilibrium"]["reached"].get<bool>());
  CHECK(settled["settle"]["max_displacement"].get<double>() > 0.0);
  // Measured again (sweep --reanalyse), a settled run keeps its settle block: what the settle did
  // cannot be recomputed from its final packing.
  const study::Reanalysed again = study::reanalyseRun(out);
  CHECK(again.after["settle"] == settled["settle"]);
  CHECK(again.after["solid_fraction"] == settled["solid_fraction"]);
  fs::remove_all(dir);
}

TEST_CASE("pipelineRunner: a run whose settle was cut short resumes at its settle, its own run kept and not redone") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_resume_settle_" + std::to_string(::getpid()));
  const fs::path runDir = dir / "runs" / "r0000";
  const fs::path kept = dir / "checkpoints" / "r0000-unsettled";
  fs::remove_all(dir);
  core::RunConfig cfg = testing::smallQuasiStaticRun("bullet", 0.0);
  cfg.compaction.timeLimit = 2.0;
  cfg.backendOptions = {{"iterations", 20}};
  const compaction::Deposit deposit = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  // As the sweep starts every attempt: an empty folder with the run's config.json.
  const auto freshFolder = [&](const core::RunConfig& c) {
    fs::remove_all(runDir);
    fs::create_directories(runDir);
    core::writeFileAtomically(runDir / "config.json", nlohmann::json(c).dump(2));
  };

  // The first attempt's settle fails (an unknown backend), after Bullet's run is finished.
  freshFolder(cfg);
  CHECK_THROWS(study::pipelineRunner(1, 300.0, "no-such-backend")(cfg, runDir, deposit, {}));
  REQUIRE(fs::exists(kept / "packing.json"));
  nlohmann::json marked = core::readJsonFile(kept / "result.json", "result");
  marked["kept"] = true;  // only a run restored from the kept folder can carry this
  core::writeFileAtomically(kept / "result.json", marked.dump(2));

  // The next attempt takes Bullet's run from the kept folder and goes straight to the settle.
  freshFolder(cfg);
  const nlohmann::json again = study::pipelineRunner(1, 300.0, "nscd")(cfg, runDir, deposit, {});
  CHECK(again == marked);
  CHECK(core::readJsonFile(runDir / study::kSettledFolder / "result.json", "settled")["equilibrium"]["reached"]
            .get<bool>());
  CHECK_FALSE(fs::exists(kept));  // the settle is done: nothing is kept

  // A kept folder of another configuration is not taken: the run is made afresh.
  fs::copy(runDir, kept, fs::copy_options::recursive);
  core::writeFileAtomically(kept / "result.json", marked.dump(2));
  core::RunConfig other = cfg;
  other.compaction.timeLimit = 1.0;
  freshFolder(other);
  const nlohmann::json afresh = study::pipelineRunner(1, 300.0, "nscd")(other, runDir, deposit, {});
  CHECK_FALSE(afresh.contains("kept"));
  CHECK(afresh["equilibrium"]["simulated_time"].get<double>() < 1.5);
  fs::remove_all(dir);
}
