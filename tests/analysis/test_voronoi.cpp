// The radical Voronoi solid fraction (analysis/voronoi.hpp) of lattices with a known phi.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/bulk_region.hpp"
#include "analysis/voronoi.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;
using confpack::testing::faceCentredCubic;
using confpack::testing::simpleCubic;

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
