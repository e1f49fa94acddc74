// Solid fraction and phi(y) profiles (analysis/solid_fraction.hpp; docs/model.md, "Solid fraction",
// "Solid-fraction profiles and their fit") against exact lattice and single-sphere answers.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/solid_fraction.hpp"
#include "analysis/sphere_geometry.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;
using confpack::testing::faceCentredCubic;
using confpack::testing::simpleCubic;

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
