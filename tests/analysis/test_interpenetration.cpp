// Interpenetration (analysis/interpenetration.hpp; docs/model.md, "Interpenetration"): exact lens
// and pinacoid overlap volumes, also across the periodic boundary.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/grain_volumes.hpp"
#include "analysis/interpenetration.hpp"
#include "analysis/solid_fraction.hpp"
#include "analysis/sphere_geometry.hpp"
#include "core/random.hpp"
#include "tests/support/lattices.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::pinacoid;
using confpack::testing::simpleCubic;

TEST_CASE("sphere interpenetration is the exact lens volume", "[analysis][interpenetration]") {
  core::Packing p = simpleCubic(6, 6, 12);
  // Push one sphere sideways into its neighbour by 0.05: lens of two caps of height 0.025.
  core::Grain& g = p.grains[5 * 36 + 2 * 6 + 2];
  REQUIRE(g.position.z() == Approx(5.5));
  g.position.x() += 0.05;
  const analysis::BulkRegion region = analysis::bulkRegion(p);
  const auto r = analysis::interpenetration(p, region);
  const double h = 0.025, cap = std::numbers::pi * h * h * (1.5 - h) / 3;
  const double grainVolume = analysis::solidFraction(p, region).grainVolume;
  CHECK(r.overlappingPairs == 1);
  CHECK(r.overlapVolume == Approx(2 * cap).epsilon(1e-12));
  CHECK(r.exactPercent == Approx(200 * cap / grainVolume).epsilon(1e-12));
  CHECK(r.maxSphereDepth == Approx(0.05));
  CHECK_FALSE(r.latticeMinPercent.has_value());
  CHECK_FALSE(r.latticeMaxPercent.has_value());
  // The touching lattice itself has no overlap.
  CHECK(analysis::interpenetration(simpleCubic(6, 6, 12), region).overlapVolume == 0.0);
}

TEST_CASE("pinacoid overlap: exact volume inside the lattice bounds", "[analysis][interpenetration]") {
  core::Packing p;
  p.box.lengthX = 6;
  p.box.width = 4;
  const core::Quat q0 = core::Quat::Identity();
  // Two aligned pinacoids (L = G = E = 1) shifted by 0.1 along y overlap over a translated copy:
  // V(A ∩ (A + t)) for t along y; cross-checked by the lattice bounds below.
  p.grains.push_back(pinacoid(1.0, core::Vec3(3.0, 2.0, 5.0), q0));
  p.grains.push_back(
      pinacoid(1.0, core::Vec3(3.05, 2.93, 5.02), core::Quat(Eigen::AngleAxisd(0.3, core::Vec3::UnitZ()))));
  const analysis::BulkRegion region{10.0, 3.0, 7.0};
  const double exactPair =
      analysis::grainOverlapVolume(p.grains[0], p.grains[1], p.grains[1].position - p.grains[0].position);
  REQUIRE(exactPair > 1e-4);
  double previousGap = 1e9;
  for (double cell : {0.1, 0.05, 0.025}) {
    analysis::InterpenetrationDef def;
    def.cell = cell;
    const auto r = analysis::interpenetration(p, region, def);
    CHECK(r.overlappingPairs == 1);
    CHECK(r.overlapVolume == Approx(exactPair).epsilon(1e-12));
    REQUIRE(r.latticeMinPercent.has_value());
    CHECK(*r.latticeMinPercent <= r.exactPercent + 1e-12);
    CHECK(r.exactPercent <= *r.latticeMaxPercent + 1e-12);
    const double gap = *r.latticeMaxPercent - *r.latticeMinPercent;
    CHECK(gap < 0.8 * previousGap);
    previousGap = gap;
  }
}

TEST_CASE("pinacoid overlap across the periodic boundary gives the same answer", "[analysis][interpenetration]") {
  core::Packing p;
  p.box.lengthX = 6;
  p.box.width = 4;
  p.box.periodicY = true;
  const core::Quat q1(Eigen::AngleAxisd(0.7, core::Vec3(1, 2, 0.5).normalized()));
  p.grains.push_back(pinacoid(1.0, core::Vec3(3.0, 2.0, 5.0), core::Quat::Identity()));
  p.grains.push_back(pinacoid(1.0, core::Vec3(3.4, 2.5, 5.3), q1));
  const analysis::BulkRegion region{10.0, 3.0, 7.0};
  const auto inside = analysis::interpenetration(p, region);
  REQUIRE(inside.overlappingPairs == 1);
  // Shift by whole numbers of cells so that the overlap straddles x = 0 and y = 0, then wrap.
  core::Packing q = p;
  for (auto& g : q.grains) g.position = q.box.wrap(g.position - core::Vec3(3.2, 2.25, 0.0));
  REQUIRE(q.grains[0].position.x() > 5.0);
  REQUIRE(q.grains[1].position.x() < 1.0);
  const auto across = analysis::interpenetration(q, region);
  CHECK(across.overlappingPairs == 1);
  CHECK(across.exactPercent == Approx(inside.exactPercent).epsilon(1e-10));
  CHECK(*across.latticeMinPercent == Approx(*inside.latticeMinPercent).epsilon(1e-8));
  CHECK(*across.latticeMaxPercent == Approx(*inside.latticeMaxPercent).epsilon(1e-8));
  CHECK(across.latticeCells == inside.latticeCells);
}
