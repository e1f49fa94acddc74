// The quasi-static protocol of a compaction (compaction.protocol, study/run_pipeline.hpp): nscd
// falls with time steps, hands over to the finisher and ends in a static equilibrium whose floor
// reaction is the weight; Bullet, which has no finisher, runs the dynamic protocol and says so.
#include <algorithm>
#include <catch2/catch.hpp>
#include <string>

#include "core/deposition.hpp"
#include "core/grain.hpp"
#include "study/run_pipeline.hpp"

using namespace confpack;

namespace {

core::RunConfig smallBox(const std::string& backend, double wallFriction) {
  core::RunConfig cfg;
  cfg.box.lengthX = 4.0;
  cfg.box.width = 3.0;
  cfg.box.height = 4.0;
  cfg.box.wallFriction = wallFriction;
  cfg.backend = backend;
  cfg.seed = 2;
  cfg.compaction.protocol = core::Protocol::QuasiStatic;
  cfg.compaction.timeLimit = 40.0;
  cfg.compaction.checkInterval = 50;
  return cfg;
}

double floorReaction(const core::Packing& p) {
  double f = 0.0;
  for (const core::Contact& c : *p.contacts)
    if (c.b == static_cast<int>(core::WallId::Floor)) f -= c.forceOnB().z();
  return f;
}

}  // namespace

TEST_CASE("quasi-static protocol: nscd hands over to the finisher and ends at rest, the floor carrying the weight") {
  const double mu = GENERATE(0.0, 0.5);
  INFO("mu_w " << mu);
  const core::RunConfig cfg = smallBox("nscd", mu);
  const core::Deposit dep = core::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  REQUIRE(dep.grains.size() > 20);
  const study::CompactionOutcome out = study::compact(cfg, dep);
  INFO(out.timing["stages"].dump());
  REQUIRE(out.reached);
  CHECK(out.protocol == core::Protocol::QuasiStatic);
  CHECK(out.timing["protocol"] == "quasi-static");
  const auto& stages = out.timing["stages"];
  REQUIRE(stages.contains("quasi_static"));
  CHECK(stages["quasi_static"]["steps"].get<long>() > 0);
  CHECK(stages["quasi_static"]["last_displacement"].get<double>() <= cfg.compaction.settleTolerance);
  // It handed over before the time limit, at a check whose kinetic ratio was below the switch.
  CHECK(stages["dynamic"]["simulated_time"].get<double>() < cfg.compaction.timeLimit);
  CHECK(stages["quasi_static"]["handed_over_at"] == "switch_kinetic_ratio");
  // Frictionless side walls: the floor carries the whole weight (rho = g = 1). With friction the
  // walls may carry part of it, never more than all of it.
  const double weight = core::totalVolume(dep.grains);
  if (mu == 0.0)
    CHECK(floorReaction(out.packing) == Approx(weight).epsilon(1e-8));
  else
    CHECK(floorReaction(out.packing) <= weight * (1.0 + 1e-8));
}

TEST_CASE("quasi-static protocol: at the time limit the finisher takes over and still ends at rest") {
  core::RunConfig cfg = smallBox("nscd", 0.0);
  cfg.compaction.timeLimit = 3.0;  // the grains are still falling onto the pile
  const core::Deposit dep = core::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  const study::CompactionOutcome out = study::compact(cfg, dep);
  const auto& stages = out.timing["stages"];
  INFO(stages.dump());
  REQUIRE(stages.contains("quasi_static"));
  CHECK(stages["quasi_static"]["handed_over_at"] == "time_limit");
  REQUIRE(out.reached);
  CHECK(floorReaction(out.packing) == Approx(core::totalVolume(dep.grains)).epsilon(1e-8));
}

// The finisher from a pile still settling, with every long step capping grains: the overlaps a
// capped grain leaves must be removed, not grow (with the trust radius alone, this pile never
// came to rest in 3,000 steps and its grains sank into one another).
TEST_CASE("quasi-static protocol: a pinacoid pile handed over early still ends at rest, without overlaps") {
  core::RunConfig cfg = smallBox("nscd", 0.0);
  cfg.box.height = 3.0;
  cfg.population.shape = core::ShapeKind::Pinacoid;
  cfg.seed = 1;
  cfg.compaction.switchKineticRatio = 1.0;  // hand over at the first check after the fall has begun
  const core::Deposit dep = core::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  REQUIRE(dep.grains.size() > 40);
  const study::CompactionOutcome out = study::compact(cfg, dep);
  INFO(out.timing["stages"].dump());
  REQUIRE(out.timing["stages"].contains("quasi_static"));
  CHECK(out.timing["stages"]["quasi_static"]["clipped_steps"].get<long>() > 0);
  REQUIRE(out.reached);
  double deepest = 0.0;
  for (const core::Contact& c : *out.packing.contacts)
    for (const core::ContactPoint& p : c.points) deepest = std::min(deepest, p.gap);
  CHECK(deepest > -1e-6);
  CHECK(floorReaction(out.packing) == Approx(core::totalVolume(dep.grains)).epsilon(1e-8));
}

TEST_CASE("quasi-static protocol: Bullet has no finisher, runs dynamic and records it") {
  core::RunConfig cfg = smallBox("bullet", 0.0);
  cfg.compaction.timeLimit = 2.0;
  const core::Deposit dep = core::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  const study::CompactionOutcome out = study::compact(cfg, dep);
  CHECK(out.protocol == core::Protocol::Dynamic);
  CHECK(out.timing["protocol"] == "dynamic");
  CHECK_FALSE(out.timing["stages"].contains("quasi_static"));
}
