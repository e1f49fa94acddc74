#pragma once
// Systems and problems shared by the nscd tests: piles that touch from the first step, one cold
// step's contact problem, and the broad phase's candidate pairs.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "backends/nscd/broad_phase.hpp"
#include "backends/nscd/contact_solver.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "compaction/deposition.hpp"
#include "core/backend.hpp"
#include "tests/support/same_bits.hpp"
#include "tests/support/systems.hpp"

namespace confpack::testing {

using core::Vec3;

/// Spheres that touch at once: a geometric deposit of `count` grains, each given its
/// placeholder's diameter (so seated on three supports or the floor).
inline core::SystemDef touchingSpheres(double lx, double w, bool periodicY, std::size_t count, std::uint64_t seed) {
  core::SystemDef s = boxSystem(lx, w, periodicY, 0.0);
  core::DepositionDef def;
  def.grainCount = count;
  const compaction::Deposit dep = compaction::deposit(s.box, core::PopulationDef{}, def, seed);
  s.grains = dep.grains;
  for (core::Grain& g : s.grains) g.size = dep.placeholderDiameter;
  return s;
}

/// A deposited pile (docs/model.md, "Deposition") of n grains between side walls with friction 0.3,
/// every grain scaled by `grow` (placeholders circumscribe the largest grain, so a plain deposit
/// touches nowhere; grown grains touch and load each other from the first step).
inline core::SystemDef pile(core::ShapeKind shape, double lengthX, double width, std::size_t n, double grow = 1.0) {
  core::SystemDef s;
  s.box.lengthX = lengthX;
  s.box.width = width;
  s.box.periodicY = false;
  s.walls.friction = 0.3;
  core::PopulationDef population;
  population.shape = shape;
  core::DepositionDef def;
  def.grainCount = n;
  s.grains = compaction::deposit(s.box, population, def, 11).grains;
  for (core::Grain& g : s.grains) g.size *= grow;
  return s;
}

/// The broad phase's candidate pairs of the grains of `s` at their initial positions.
inline std::vector<nscd::CandidatePair> candidatePairs(const core::SystemDef& s, const nscd::NarrowPhase& narrow) {
  std::vector<Vec3> positions;
  std::vector<double> reach;
  for (std::size_t i = 0; i < s.grains.size(); ++i) {
    positions.push_back(s.grains[i].position);
    reach.push_back(narrow.reach(static_cast<int>(i)));
  }
  std::vector<nscd::CandidatePair> pairs;
  nscd::BroadPhase(s.box, narrow.maxReach()).findPairs(positions, reach, pairs);
  return pairs;
}

/// One step's contact problem of the grains of `s` at rest, solved cold (no warm start) with
/// `settings`: contacts from the broad and narrow phases at the grains' positions, inverse masses
/// (the last body is the static walls), velocities kicked by gravity over dt = 2e-3 and then
/// corrected by the solve. solveAgain() solves the same problem again with the same solver, which
/// keeps what its solves carry from one to the next (the "switching" preconditioner's state).
struct ColdStep {
  static constexpr double kDt = 2e-3;
  core::SystemDef system;
  std::vector<Vec3> positions;
  std::vector<nscd::BodyInverseMass> bodies;
  std::vector<nscd::BodyVelocity> velocities;
  std::vector<nscd::ContactGeometry> contacts;
  nscd::ContactSolver solver;
  int iterations = 0;

  ColdStep(const core::SystemDef& s, const nscd::NscdSettings& settings, int threads = 1)
      : system(s), bodies(s.grains.size() + 1), velocities(s.grains.size() + 1) {
    nscd::NarrowPhase narrow(s.box, s.grains, settings.alertDistance);
    nscd::BroadPhase broad(s.box, narrow.maxReach());
    std::vector<core::Quat> orientations;
    std::vector<double> reach;
    for (std::size_t i = 0; i < s.grains.size(); ++i) {
      const core::Grain& g = s.grains[i];
      positions.push_back(g.position);
      orientations.push_back(g.orientation);
      reach.push_back(narrow.reach(static_cast<int>(i)));
      bodies[i].invMass = 1.0 / (s.density * g.volume());
      bodies[i].invInertia = g.bodyInertia(s.density).inverse();
    }
    std::vector<nscd::CandidatePair> pairs;
    broad.findPairs(positions, reach, pairs);
    narrow.collideAll(pairs, positions, orientations, contacts, 1);
    iterations = solveAgain(settings, threads);
  }

  /// The step solved afresh from the grains at rest; returns (and keeps) its iterations.
  int solveAgain(const nscd::NscdSettings& settings, int threads = 1) {
    for (std::size_t i = 0; i + 1 < velocities.size(); ++i)
      velocities[i] = {Vec3(0.0, 0.0, -kDt), Vec3::Zero()};  // g = 1
    solver.prepare(contacts, positions, bodies, system.box, system.walls, kDt, settings);
    solver.warmStart(nscd::ContactCache{}, contacts, kDt, velocities);
    return iterations = solver.solve(velocities, settings, threads);
  }
};

/// Largest linear or angular speed of any grain after the step (the static-walls body left out).
inline double largestSpeed(const ColdStep& step) {
  double largest = 0.0;
  for (std::size_t i = 0; i + 1 < step.velocities.size(); ++i)
    largest = std::max({largest, step.velocities[i].v.norm(), step.velocities[i].w.norm()});
  return largest;
}

/// Largest grain speed of step a, and largest difference of grain velocities between steps a and
/// b of the same system (the static-walls body left out).
struct VelocityComparison {
  double largest = 0.0;
  double difference = 0.0;
};
inline VelocityComparison compareVelocities(const ColdStep& a, const ColdStep& b) {
  VelocityComparison c;
  for (std::size_t i = 0; i + 1 < a.velocities.size(); ++i) {
    c.largest = std::max(c.largest, a.velocities[i].v.norm());
    c.difference = std::max(c.difference, (a.velocities[i].v - b.velocities[i].v).norm());
  }
  return c;
}

/// A column of `beads` touching unit spheres on the floor of a 5 x 5 box, one cold step with
/// `settings`, checked: stopped dead (to `relative` of a step's fall), and the contact under bead j
/// (0 the lowest; the floor under bead 0) carrying the beads j.., (beads - j) m g dt, to `relative`.
/// Returns the step for further checks.
inline std::unique_ptr<ColdStep> checkBeadColumn(const nscd::NscdSettings& settings, int beads, double relative) {
  core::SystemDef s = boxSystem(5.0, 5.0, false, 0.0);
  for (int k = 0; k < beads; ++k) s.grains.push_back(sphere(1.0, Vec3(2.5, 2.5, 0.5 + k)));
  auto step = std::make_unique<ColdStep>(s, settings);
  REQUIRE(step->contacts.size() == static_cast<std::size_t>(beads));  // floor + beads - 1 pairs
  CHECK(step->solver.residual() < settings.tolerance);
  CHECK(largestSpeed(*step) < relative * ColdStep::kDt);
  const double weight = s.grains[0].volume() * ColdStep::kDt;
  for (std::size_t c = 0; c < step->contacts.size(); ++c) {
    const nscd::ContactGeometry& g = step->contacts[c];
    const int carried = g.b < 0 ? beads : beads - 1 - std::min(g.a, g.b);
    INFO("contact " << c << " between " << g.a << " and " << g.b);
    CHECK(step->solver.normalImpulse(static_cast<int>(c), 0) == Approx(carried * weight).epsilon(relative));
  }
  return step;
}

/// A bidisperse pyramid, one cold step with `settings`, checked to `relative` of a step's fall:
/// four unit spheres on the floor of a box of length 4 (periodic in x, so they touch in a ring)
/// and width 1.2, and two spheres of d_S = 1/2 each resting in the groove of a pair: a small
/// centre 1/2 from each of its two supports' along x and h = sqrt(((1 + d_S) / 2)^2 - 1/4) above
/// them. Stopped dead, and (unique, where the ring's compression is not) each small sphere's two
/// contacts carry m_S g dt / (2 cos theta) with cos theta = h / ((1 + d_S) / 2), the floor under
/// each unit sphere (m_L + m_S / 2) g dt. Returns the step for further checks.
inline std::unique_ptr<ColdStep> checkBidispersePyramid(const nscd::NscdSettings& settings, double relative) {
  constexpr double kSmall = 0.5;
  const double reach = 0.5 * (1.0 + kSmall);
  const double h = std::sqrt(reach * reach - 0.25);
  core::SystemDef s = boxSystem(4.0, 1.2, false, 0.0);
  for (int k = 0; k < 4; ++k) s.grains.push_back(sphere(1.0, Vec3(0.5 + k, 0.6, 0.5)));
  for (double x : {1.0, 3.0}) s.grains.push_back(sphere(kSmall, Vec3(x, 0.6, 0.5 + h)));
  auto step = std::make_unique<ColdStep>(s, settings);
  CHECK(step->solver.residual() < settings.tolerance);
  CHECK(largestSpeed(*step) < relative * ColdStep::kDt);
  const double massLarge = s.grains[0].volume(), massSmall = s.grains[4].volume();  // rho = 1
  const double onGroove = massSmall * ColdStep::kDt / (2.0 * h / reach);
  const double onFloor = (massLarge + 0.5 * massSmall) * ColdStep::kDt;
  int grooves = 0, floors = 0;
  for (std::size_t c = 0; c < step->contacts.size(); ++c) {
    const nscd::ContactGeometry& g = step->contacts[c];
    const double r = step->solver.normalImpulse(static_cast<int>(c), 0);
    INFO("contact " << c << " between " << g.a << " and " << g.b << ", normal " << g.normal.transpose());
    if (g.b < 0 && std::abs(g.normal.z()) > 0.5) {
      ++floors;
      CHECK(r == Approx(onFloor).epsilon(relative));
    } else if (g.b >= 4 || g.a >= 4) {
      ++grooves;
      CHECK(r == Approx(onGroove).epsilon(relative));
    }
  }
  CHECK(floors == 4);
  CHECK(grooves == 4);
  return step;
}

}  // namespace confpack::testing
