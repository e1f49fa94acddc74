// Solid fraction, phi(y) profiles and interpenetration against exact answers
// (docs/model.md, "Interpenetration", "Solid fraction", "Solid-fraction profiles and their fit").
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/grain_volumes.hpp"
#include "analysis/interpenetration.hpp"
#include "analysis/solid_fraction.hpp"
#include "analysis/sphere_geometry.hpp"
#include "analysis/voronoi.hpp"
#include "core/random.hpp"
#include "lattices.hpp"

using namespace confpack;
using analysis::testing::faceCentredCubic;
using analysis::testing::simpleCubic;

TEST_CASE("simple cubic lattice has phi = pi/6", "[analysis][phi]") {
  const core::Packing p = simpleCubic(5, 4, 12);
  const analysis::BulkRegion region = analysis::bulkRegion(p);  // 3 < z < 9: lattice planes
  const auto s = analysis::solidFraction(p, region);
  CHECK(s.phi == Approx(std::numbers::pi / 6).epsilon(1e-12));
  // Through sphere centres too (half spheres on each side).
  const auto c = analysis::solidFraction(p, analysis::BulkRegion{12.0, 2.5, 8.5});
  CHECK(c.phi == Approx(std::numbers::pi / 6).epsilon(1e-12));
  // Not aligned: differs (the z-profile of SC oscillates).
  const auto off = analysis::solidFraction(p, analysis::BulkRegion{12.0, 2.5, 2.8});
  CHECK(off.phi > std::numbers::pi / 6 * 1.1);
}

TEST_CASE("fcc lattice has phi = pi / (3 sqrt 2)", "[analysis][phi]") {
  const core::Packing p = faceCentredCubic(3, 6);
  const double a = std::sqrt(2.0);
  // Any slab spanning a whole number of cubic cells along z.
  for (double z0 : {2.0, 3.1, 3.7}) {
    const auto s = analysis::solidFraction(p, analysis::BulkRegion{20.0, z0, z0 + 2 * a});
    CHECK(s.phi == Approx(std::numbers::pi / (3 * std::sqrt(2.0))).epsilon(1e-12));
  }
}

TEST_CASE("phi(y) profile of one sphere follows pi (r^2 - y^2)", "[analysis][phi]") {
  core::Packing p;
  p.box.lengthX = 4;
  p.box.width = 4;
  core::Grain g;
  g.size = 1.4;
  g.position = core::Vec3(1.0, 1.7, 5.0);
  p.grains.push_back(g);
  analysis::ProfileDef def;
  def.fold = false;
  const analysis::BulkRegion region{10.0, 3.0, 7.0};
  const auto prof = analysis::solidFractionProfile(p, region, def);
  REQUIRE(prof.y.size() == 200);
  CHECK(prof.slice == Approx(0.02));
  const double r = 0.7, norm = p.box.lengthX * region.height();
  double total = 0.0;
  for (std::size_t k = 0; k < prof.y.size(); ++k) {
    const double dy = prof.y[k] - g.position.y();
    // Mean of pi (r^2 - s^2) over the slice, exactly: pi (r^2 - dy^2 - h^2/12) inside the sphere.
    if (std::abs(dy) < r - prof.slice) {
      const double expected = std::numbers::pi * (r * r - dy * dy - prof.slice * prof.slice / 12) / norm;
      CHECK(prof.phi[k] == Approx(expected).epsilon(1e-9));
    }
    total += prof.phi[k] * prof.slice * norm;
  }
  CHECK(total == Approx(analysis::sphereVolume(r)).epsilon(1e-12));
  // Folding averages the two walls.
  const auto folded = analysis::solidFractionProfile(p, region);
  REQUIRE(folded.folded);
  REQUIRE(folded.phi.size() == 100);
  CHECK(folded.phi[10] == Approx(0.5 * (prof.phi[10] + prof.phi[189])));
  // A biperiodic box wraps a grain straddling y = W onto both sides.
  p.box.periodicY = true;
  p.grains[0].position.y() = 3.9;
  const auto wrapped = analysis::solidFractionProfile(p, region, def);
  CHECK_FALSE(wrapped.folded);
  CHECK(wrapped.phi[0] > 0.0);
  CHECK(wrapped.phi[199] > 0.0);
  double sum = 0.0;
  for (double v : wrapped.phi) sum += v * wrapped.slice * norm;
  CHECK(sum == Approx(analysis::sphereVolume(r)).epsilon(1e-12));
}

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

namespace {
core::Grain pinacoid(const core::Vec3& x, const core::Quat& q, double size = 1.0) {
  core::Grain g;
  g.shape = core::ShapeKind::Pinacoid;
  g.size = size;
  g.position = x;
  g.orientation = q;
  return g;
}
}  // namespace

TEST_CASE("pinacoid slab volumes: partition sums and Monte Carlo", "[analysis][pinacoid]") {
  core::Rng rng(7, core::StreamId::Test);
  const core::Grain g = pinacoid(core::Vec3(2.0, 3.0, 4.0), rng.uniformQuaternion(), 1.1);
  std::vector<double> edges;
  for (double z = 3.0; z <= 5.0 + 1e-12; z += 0.1) edges.push_back(z);
  const std::vector<double> v = analysis::grainSlabVolumes(g, 2, edges);
  double sum = 0.0;
  for (double x : v) sum += x;
  CHECK(sum == Approx(g.volume()).epsilon(1e-11));
  // Monte Carlo of the slab 3.9 < z < 4.25 in the bounding cube.
  const analysis::PlacedGrain placed(g);
  const core::Mat3 rt = placed.placed.rotation.transpose();
  const double R = g.boundingRadius();
  const int samples = 200000;
  int hits = 0;
  for (int s = 0; s < samples; ++s) {
    const core::Vec3 x = g.position + core::Vec3(rng.uniform(-R, R), rng.uniform(-R, R), rng.uniform(-R, R));
    if (x.z() > 3.9 && x.z() < 4.25 && placed.shape.contains(rt * (x - g.position))) ++hits;
  }
  const double mc = 8 * R * R * R * hits / samples;
  const double sigma = 8 * R * R * R * std::sqrt(hits * (1.0 - double(hits) / samples)) / samples;
  CHECK(std::abs(analysis::grainSlabVolume(g, 2, 3.9, 4.25) - mc) < 4 * sigma);
}

TEST_CASE("pinacoid overlap: exact volume inside the lattice bounds", "[analysis][interpenetration]") {
  core::Packing p;
  p.box.lengthX = 6;
  p.box.width = 4;
  const core::Quat q0 = core::Quat::Identity();
  // Two aligned pinacoids (L = G = E = 1) shifted by 0.1 along y overlap over a translated copy:
  // V(A ∩ (A + t)) for t along y; cross-checked by the lattice bounds below.
  p.grains.push_back(pinacoid(core::Vec3(3.0, 2.0, 5.0), q0));
  p.grains.push_back(pinacoid(core::Vec3(3.05, 2.93, 5.02), core::Quat(Eigen::AngleAxisd(0.3, core::Vec3::UnitZ()))));
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

TEST_CASE("radical Voronoi check of lattice solid fractions", "[analysis][phi][voronoi]") {
  const core::Packing sc = simpleCubic(5, 5, 12);
  const auto v = analysis::voronoiSolidFraction(sc, analysis::bulkRegion(sc));
  REQUIRE(v.has_value());  // the build has voro++ (Debian voro++-dev)
  CHECK(v->cells == 5 * 5 * 6);
  CHECK(v->phi == Approx(std::numbers::pi / 6).epsilon(1e-9));
  const core::Packing fcc = faceCentredCubic(4, 6);
  const auto f = analysis::voronoiSolidFraction(fcc, analysis::BulkRegion{10.0, 2.0, 6.0});
  REQUIRE(f.has_value());
  CHECK(f->phi == Approx(std::numbers::pi / (3 * std::sqrt(2.0))).epsilon(1e-9));
  // Walls: the spheres of a lattice touching both side walls fill cells cut by the walls.
  core::Packing walled = sc;
  walled.box.periodicY = false;
  CHECK(analysis::voronoiSolidFraction(walled, analysis::bulkRegion(walled))->phi ==
        Approx(std::numbers::pi / 6).epsilon(1e-9));
  // Polydisperse: radical cells still hold their spheres; a shrunk sphere lowers phi by its volume loss.
  core::Packing poly = sc;
  poly.grains[5 * 25 + 12].size = 0.8;
  const auto p = analysis::voronoiSolidFraction(poly, analysis::bulkRegion(poly));
  const double loss = (1.0 - 0.8 * 0.8 * 0.8) * std::numbers::pi / 6;
  CHECK(p->phi == Approx((150 * std::numbers::pi / 6 - loss) / 150.0).epsilon(1e-6));
}

TEST_CASE("pinacoid overlap across the periodic boundary gives the same answer", "[analysis][interpenetration]") {
  core::Packing p;
  p.box.lengthX = 6;
  p.box.width = 4;
  p.box.periodicY = true;
  const core::Quat q1(Eigen::AngleAxisd(0.7, core::Vec3(1, 2, 0.5).normalized()));
  p.grains.push_back(pinacoid(core::Vec3(3.0, 2.0, 5.0), core::Quat::Identity()));
  p.grains.push_back(pinacoid(core::Vec3(3.4, 2.5, 5.3), q1));
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
