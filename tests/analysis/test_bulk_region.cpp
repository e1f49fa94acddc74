// The free surface and the bulk region (analysis/bulk_region.hpp; docs/model.md, "Bulk region and
// free surface") of a flat lattice.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/bulk_region.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;
using confpack::testing::simpleCubic;

TEST_CASE("free surface and bulk region of a flat lattice", "[analysis][bulk]") {
  const core::Packing p = simpleCubic(6, 4, 10);
  const analysis::BulkRegion r = analysis::bulkRegion(p);
  CHECK(r.freeSurface == Approx(10.0));
  CHECK(r.zLow == 3.0);
  CHECK(r.zHigh == Approx(7.0));
  CHECK(r.contains(5.5));
  CHECK_FALSE(r.contains(2.5));
  CHECK_FALSE(r.contains(7.5));
  CHECK(r.volume(p.box) == Approx(6 * 4 * 4.0));

  // One loose grain on top moves the mean by (1 / number of cells) of its height only.
  core::Packing q = p;
  core::Grain extra = q.grains.front();
  extra.position = core::Vec3(0.5, 0.5, 10.5);
  q.grains.push_back(extra);
  analysis::BulkRegionDef def;
  def.cellSize = 2.0;  // 3 x 2 cells
  CHECK(analysis::freeSurfaceHeight(q, def.cellSize) == Approx(10.0 + 1.0 / 6.0));

  def.cellSize = -1.0;
  CHECK_THROWS_AS(analysis::bulkRegion(p, def), std::invalid_argument);
}
