// compaction/compaction.hpp: compaction with the adaptive time step (compaction/time_step.hpp)
// and with the quasi-static protocol.
//
// The adaptive time step of a compaction (compaction.adaptive_dt): the
// step keeps every grain within a hundredth of the smallest grain size per step at its current
// speed, and a pile compacted with it ends in a true static equilibrium (forces are impulses over
// the step that made them, whatever its length).
//
// The quasi-static protocol of a compaction (compaction.protocol): nscd
// falls with time steps, hands over to the finisher and ends in a static equilibrium whose floor
// reaction is the weight; Bullet, which has no finisher, runs the dynamic protocol and says so.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "analysis/coordination.hpp"
#include "analysis/rigidity.hpp"
#include "compaction/compaction.hpp"
#include "compaction/deposition.hpp"
#include "compaction/time_step.hpp"
#include "core/box.hpp"
#include "core/grain.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;

namespace {

core::Grain sphereOf(double d) {
  return testing::sphere(d, core::Vec3::Zero());
}

core::BodyState moving(const core::Vec3& v, const core::Vec3& omega = core::Vec3::Zero()) {
  core::BodyState s;
  s.velocity = v;
  s.angularVelocity = omega;
  return s;
}

core::RunConfig smallBox(const std::string& backend, double wallFriction) {
  return testing::smallQuasiStaticRun(backend, wallFriction);
}

double floorReaction(const core::Packing& p) {
  double f = 0.0;
  for (const core::Contact& c : *p.contacts)
    if (c.b == static_cast<int>(core::WallId::Floor)) f -= c.forceOnB().z();
  return f;
}

/// cfg's deposit (of its own seed) and its compaction.
struct Compacted {
  compaction::Deposit deposit;
  compaction::CompactionOutcome outcome;
};

Compacted depositAndCompact(const core::RunConfig& cfg) {
  compaction::Deposit dep = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  compaction::CompactionOutcome out = compaction::compact(cfg, dep);
  return {std::move(dep), std::move(out)};
}

}  // namespace

TEST_CASE("adaptive step: v dt + g dt^2 / 2 equals a hundredth of the smallest grain") {
  const double g = 1.0, floor = 1e-4, previous = 1e9;  // no clamp in play
  const std::vector<core::Grain> mono(3, sphereOf(1.0));

  SECTION("grains at rest: the free fall from rest covers d/100, dt = sqrt(2 s / g)") {
    const std::vector<core::BodyState> rest(3, moving(core::Vec3::Zero()));
    const double dt = compaction::AdaptiveTimeStep(mono, g, floor).next(previous, rest);
    CHECK(dt == Approx(std::sqrt(0.02)).epsilon(1e-12));
  }
  SECTION("the fastest grain sets the step: v = 0.5 gives dt = sqrt(v^2 + 2 g s) - v") {
    const std::vector<core::BodyState> states = {moving({0.1, 0, 0}), moving({0, -0.3, -0.4}), moving({0, 0, 0})};
    const double dt = compaction::AdaptiveTimeStep(mono, g, floor).next(previous, states);
    CHECK(dt == Approx(std::sqrt(0.25 + 0.02) - 0.5).epsilon(1e-12));
    CHECK(0.5 * dt + 0.5 * g * dt * dt == Approx(0.01).epsilon(1e-12));
  }
  SECTION("a spinning pinacoid counts with the speed of its surface, omega r; a spinning sphere does not move") {
    const std::vector<core::BodyState> spinning = {moving(core::Vec3::Zero(), {0, 0, 1.0}), moving(core::Vec3::Zero()),
                                                   moving(core::Vec3::Zero())};
    std::vector<core::Grain> withPinacoid = mono;
    withPinacoid[0] = testing::pinacoid(1.0, core::Vec3::Zero());
    const double r = withPinacoid[0].boundingRadius();
    CHECK(compaction::AdaptiveTimeStep(withPinacoid, g, floor).next(previous, spinning) ==
          Approx(std::sqrt(r * r + 0.02) - r).epsilon(1e-12));
    // The sphere's spin leaves its boundary where it is: the step of grains at rest.
    CHECK(compaction::AdaptiveTimeStep(mono, g, floor).next(previous, spinning) ==
          Approx(std::sqrt(0.02)).epsilon(1e-12));
  }
  SECTION("a bidisperse sample is bounded by its small grains: s = d_S / 100") {
    const std::vector<core::Grain> bi = {sphereOf(1.0), sphereOf(0.5), sphereOf(1.0)};
    const std::vector<core::BodyState> rest(3, moving(core::Vec3::Zero()));
    CHECK(compaction::AdaptiveTimeStep(bi, g, floor).next(previous, rest) == Approx(std::sqrt(0.01)).epsilon(1e-12));
  }
  SECTION("clamped: never below the fixed step, never more than kAdaptiveGrowth x the step before") {
    const std::vector<core::BodyState> fast(3, moving({0, 0, -10.0}));
    CHECK(compaction::AdaptiveTimeStep(mono, g, 2e-3).next(previous, fast) == 2e-3);  // the rule alone gives ~1e-3
    const std::vector<core::BodyState> rest(3, moving(core::Vec3::Zero()));
    CHECK(compaction::AdaptiveTimeStep(mono, g, floor).next(0.01, rest) == Approx(compaction::kAdaptiveGrowth * 0.01));
  }
}

TEST_CASE("adaptive step: a deposit compacts to equilibrium, the floor carries the weight, with either backend") {
  const std::string backend = GENERATE(std::string("nscd"), std::string("bullet"));
  INFO("backend " << backend);
  core::RunConfig cfg;
  cfg.box.lengthX = 4.0;
  cfg.box.width = 3.0;
  cfg.box.height = 4.0;
  cfg.backend = backend;
  cfg.seed = 2;
  cfg.compaction.adaptiveDt = true;
  cfg.compaction.timeLimit = 150.0;
  cfg.compaction.checkInterval = 50;
  const auto [dep, out] = depositAndCompact(cfg);
  REQUIRE(dep.grains.size() > 20);
  INFO(out.equilibrium.dump());
  // Bullet's sequential impulses do not meet the equilibrium test's force bound (README, Known
  // limitations): only its floor reaction is checked, to its own accuracy.
  if (backend == "nscd") REQUIRE(out.reached);
  // The step grew well past the fixed step once the pile stopped falling.
  CHECK(out.dtLargest > 10.0 * out.dt);
  // ... and equilibrium was still checked at least every kAdaptiveCheckSpacing of simulated time.
  REQUIRE(out.history.size() > 2);
  for (std::size_t k = 1; k < out.history.size(); ++k)
    CHECK(out.history[k].time - out.history[k - 1].time <= compaction::kAdaptiveCheckSpacing + out.dtLargest);
  // Frictionless side walls: the floor carries the whole weight (rho = g = 1), through forces
  // computed from the impulses of a step of the last step's own length.
  REQUIRE(out.packing.contacts.has_value());
  CHECK(floorReaction(out.packing) == Approx(core::totalVolume(dep.grains)).epsilon(backend == "nscd" ? 1e-6 : 1e-2));
}

TEST_CASE("quasi-static protocol: nscd hands over to the finisher and ends at rest, the floor carrying the weight") {
  const double mu = GENERATE(0.0, 0.5);
  INFO("mu_w " << mu);
  const core::RunConfig cfg = smallBox("nscd", mu);
  const auto [dep, out] = depositAndCompact(cfg);
  REQUIRE(dep.grains.size() > 20);
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
  CHECK(stages["quasi_static"]["mean_kinetic_ratio_at_hand_over"].get<double>() < cfg.compaction.switchKineticRatio);
  // A sphere pile's finisher solves with the interior point ("auto") from the start.
  CHECK(stages["quasi_static"]["solver"] == "ipm");
  CHECK(stages["quasi_static"]["switched_from_mprgp"] == false);
  // Frictionless side walls: the floor carries the whole weight (rho = g = 1). With friction the
  // walls may carry part of it, never more than all of it.
  const double weight = core::totalVolume(dep.grains);
  if (mu == 0.0)
    CHECK(floorReaction(out.packing) == Approx(weight).epsilon(1e-8));
  else
    CHECK(floorReaction(out.packing) <= weight * (1.0 + 1e-8));
  // Rigid, frictionless and at rest: the contact network is isostatic, no self-stress (Roux,
  // PRE 61, 6802, 2000), whatever the pile's local coordination.
  if (mu == 0.0) {
    const auto rigidity = analysis::contactRigidity(
        out.packing, analysis::forceCarryingContacts(out.packing, *out.packing.contacts, false));
    REQUIRE(rigidity.has_value());
    CHECK(rigidity->contacts > 2 * static_cast<int>(dep.grains.size()));
    CHECK(rigidity->selfStresses() == 0);
  }
}

TEST_CASE("quasi-static protocol: spheres spun by wall friction do not hold the fall back") {
  // The quick study's W = 3, mu_w = 0.5 pile of seed 2 (95 spheres). Wall friction spins spheres,
  // and a sphere that leaves the wall keeps its spin (its other contacts are frictionless); with
  // the spin counted, this fall ran to its 30 t0 limit, the mean kinetic ratio still 1.4e-4.
  core::RunConfig cfg = smallBox("nscd", 0.5);
  cfg.box.height = 7.0;
  cfg.compaction.fallTimeLimit = 30.0;
  cfg.compaction.checkInterval = 200;
  cfg.compaction.settleTolerance = 1e-6;
  const auto [dep, out] = depositAndCompact(cfg);
  const auto& stages = out.timing["stages"];
  INFO(stages.dump());
  REQUIRE(stages.contains("quasi_static"));
  CHECK(stages["quasi_static"]["handed_over_at"] == "switch_kinetic_ratio");
  CHECK(stages["dynamic"]["simulated_time"].get<double>() < 20.0);
  REQUIRE(out.reached);
  CHECK(floorReaction(out.packing) <= core::totalVolume(dep.grains) * (1.0 + 1e-8));
}

TEST_CASE("quasi-static protocol: at the time limit the finisher takes over and still ends at rest") {
  core::RunConfig cfg = smallBox("nscd", 0.0);
  cfg.compaction.timeLimit = 3.0;  // the grains are still falling onto the pile
  const auto [dep, out] = depositAndCompact(cfg);
  const auto& stages = out.timing["stages"];
  INFO(stages.dump());
  REQUIRE(stages.contains("quasi_static"));
  CHECK(stages["quasi_static"]["handed_over_at"] == "time_limit");
  // Still falling: result.json says how far from the switch the fall was.
  CHECK(stages["quasi_static"]["mean_kinetic_ratio_at_hand_over"].get<double>() > cfg.compaction.switchKineticRatio);
  REQUIRE(out.reached);
  CHECK(floorReaction(out.packing) == Approx(core::totalVolume(dep.grains)).epsilon(1e-8));
}

// nscd's fall_tolerance loosens the fall's solves only: the finisher, with its own threshold,
// still balances the pile, so the floor carries the weight to the finisher's accuracy
// (settle_tolerance, 1e-6 d, for pinacoids; the interior-point solves of sphere piles do better).
// Sphere piles keep the tight solves unless told ("auto"); pinacoid piles loosen them by default.
TEST_CASE("quasi-static protocol: a fall solved to 1e-6 takes fewer iterations and still ends in equilibrium") {
  const bool pinacoids = GENERATE(false, true);
  INFO((pinacoids ? "pinacoids" : "spheres"));
  core::RunConfig cfg = smallBox("nscd", 0.0);
  if (pinacoids) {
    cfg.box.height = 3.0;
    cfg.population.shape = core::ShapeKind::Pinacoid;
  }
  const compaction::Deposit dep = compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  const auto compactWith = [&](const nlohmann::json& options) {
    core::RunConfig c = cfg;
    c.backendOptions = options;
    return compaction::compact(c, dep);
  };
  const compaction::CompactionOutcome tight =
      compactWith(pinacoids ? nlohmann::json{{"fall_tolerance", 1e-10}} : nlohmann::json::object());
  const compaction::CompactionOutcome loose =
      compactWith(pinacoids ? nlohmann::json::object() : nlohmann::json{{"fall_tolerance", 1e-6}});
  INFO(tight.timing["stages"].dump() << "\n" << loose.timing["stages"].dump());
  REQUIRE(tight.reached);
  REQUIRE(loose.reached);
  CHECK(loose.timing["stages"]["dynamic"]["iterations"].get<double>() <
        0.8 * tight.timing["stages"]["dynamic"]["iterations"].get<double>());
  CHECK(floorReaction(loose.packing) == Approx(core::totalVolume(dep.grains)).epsilon(pinacoids ? 1e-6 : 1e-8));
}

// fall_time_limit bounds nscd's fall and leaves time_limit to Bullet, which has no finisher: one
// study can give nscd's piles the fall they need and stop Bullet early (reproduce --scale quick).
TEST_CASE("quasi-static protocol: fall_time_limit bounds nscd's fall, time_limit Bullet's run") {
  for (const std::string backend : {"nscd", "bullet"}) {
    INFO(backend);
    core::RunConfig cfg = smallBox(backend, 0.0);
    cfg.compaction.timeLimit = 0.5;
    cfg.compaction.fallTimeLimit = 3.0;  // the grains are still falling onto the pile at 3 t0
    const auto [dep, out] = depositAndCompact(cfg);
    const auto& stages = out.timing["stages"];
    INFO(stages.dump());
    const double fell = stages["dynamic"]["simulated_time"].get<double>();
    if (backend == "nscd") {
      CHECK(fell == Approx(3.0).margin(out.dt));
      CHECK(stages["quasi_static"]["handed_over_at"] == "fall_time_limit");
      CHECK(out.reached);
    } else {
      CHECK(fell == Approx(0.5).margin(out.dt));
      CHECK_FALSE(stages.contains("quasi_static"));
      CHECK_FALSE(out.reached);
    }
  }
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
  const auto [dep, out] = depositAndCompact(cfg);
  REQUIRE(dep.grains.size() > 40);
  INFO(out.timing["stages"].dump());
  REQUIRE(out.timing["stages"].contains("quasi_static"));
  CHECK(out.timing["stages"]["quasi_static"]["clipped_steps"].get<long>() > 0);
  REQUIRE(out.reached);
  double deepest = 0.0;
  for (const core::Contact& c : *out.packing.contacts)
    for (const core::ContactPoint& p : c.points) deepest = std::min(deepest, p.gap);
  CHECK(deepest > -1e-6);
  // The finisher stops once no grain moved more than settle_tolerance (1e-6 d) in its last step;
  // the floor carries the weight to that relative accuracy.
  CHECK(floorReaction(out.packing) == Approx(core::totalVolume(dep.grains)).epsilon(1e-6));
}

TEST_CASE("quasi-static protocol: Bullet has no finisher, runs dynamic and records it") {
  core::RunConfig cfg = smallBox("bullet", 0.0);
  cfg.compaction.timeLimit = 2.0;
  const auto [dep, out] = depositAndCompact(cfg);
  CHECK(out.protocol == core::Protocol::Dynamic);
  CHECK(out.timing["protocol"] == "dynamic");
  CHECK_FALSE(out.timing["stages"].contains("quasi_static"));
}
