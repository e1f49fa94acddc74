// Cell counts (analysis/cell_count.hpp): a whole number of cells near the requested side, and a
// count too large refused by name instead of clamped.
#include <catch2/catch.hpp>

#include "analysis/cell_count.hpp"
#include "analysis/solid_fraction.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;

TEST_CASE("cells along a length: the nearest whole number, at least one", "[analysis][cell_count]") {
  CHECK(analysis::cellsAlong(4.0, 0.02, "slice") == 200);
  CHECK(analysis::cellsAlong(4.0, 0.03, "slice") == 133);
  CHECK(analysis::cellsAlong(4.0, 10.0, "slice") == 1);
  CHECK(analysis::cellsAlong(0.0, 0.1, "slice") == 1);
  CHECK(analysis::cellsAlong(100.0, 100.0 / analysis::kMaxCellsAlongAxis, "slice") == 100'000'000);
}

TEST_CASE("a slice too thin for a profile is refused by name, not replaced by one slice", "[analysis][cell_count]") {
  // The failure this guards against: --slice 1e-9 over W = 4 wrapped past an int and came out as one slice
  // 4 d_L thick, exit 0.
  CHECK_THROWS_WITH(analysis::cellsAlong(4.0, 1e-9, "profile: slice"),
                    "profile: slice of 1e-09 d_L over 4 d_L makes 4e+09 cells, more than the 1e+08 one axis can "
                    "hold; give a larger one");
  const core::Packing p = testing::simpleCubic(4, 4, 3);
  analysis::ProfileDef def;
  def.slice = 1e-9;
  CHECK_THROWS_WITH(analysis::solidFractionProfile(p, analysis::BulkRegion{3.0, 0.5, 2.5}, def),
                    Catch::StartsWith("profile: slice of 1e-09 d_L"));
}
