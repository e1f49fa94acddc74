// Homogeneity (analysis/homogeneity.hpp; docs/model.md, "Homogeneity"): large and small grains counted per layer.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/bulk_region.hpp"
#include "analysis/homogeneity.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;
using confpack::testing::simpleCubic;

TEST_CASE("homogeneity counts large and small grains per layer", "[analysis][homogeneity]") {
  core::Packing p = simpleCubic(4, 4, 8);
  // Make the grains of every second layer small (their centres stay put).
  for (auto& g : p.grains)
    if (static_cast<int>(g.position.z()) % 2 == 1) g.size = 0.5;
  // And in the bulk, the column y in [0, 1) small too.
  for (auto& g : p.grains)
    if (g.position.y() < 1.0) g.size = 0.5;
  const auto h = analysis::homogeneity(p, analysis::bulkRegion(p));
  REQUIRE(h.alongZ.pLarge.size() == 8);
  CHECK(h.alongZ.pLarge[0] == Approx(12.0 / 16.0));
  CHECK(h.alongZ.pSmall[1] == Approx(1.0));
  REQUIRE(h.alongY.pLarge.size() == 4);
  CHECK(h.alongY.pSmall[0] == Approx(1.0));
  // Bulk layers z = 3.5 (large except y column) and 4.5 (small): half of each y-layer is large.
  CHECK(h.alongY.pLarge[2] == Approx(0.5));
  CHECK(h.alongY.large[2] + h.alongY.small[2] == 8);
}
