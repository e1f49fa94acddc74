// analysis/displacement.hpp: how far the grains moved between two packings of the same grains.
#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "analysis/displacement.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;

TEST_CASE("displacement: the largest and mean centre displacement, the minimum image across the period") {
  core::BoxDef box;
  box.lengthX = 4.0;
  box.width = 3.0;
  const std::vector<core::Grain> before = {testing::sphere(1.0, core::Vec3(0.1, 1.0, 0.5)),
                                           testing::sphere(1.0, core::Vec3(2.0, 1.5, 0.5)),
                                           testing::sphere(1.0, core::Vec3(3.0, 1.5, 2.0))};
  std::vector<core::Grain> after = before;
  after[0].position.x() = 3.9;                      // across the period: 0.2, not 3.8
  after[1].position += core::Vec3(0.0, 0.3, -0.4);  // 0.5
  const analysis::Displacement d = analysis::displacement(box, before, after);
  CHECK(d.max == Approx(0.5));
  CHECK(d.maxGrain == 1);
  CHECK(d.mean == Approx((0.2 + 0.5 + 0.0) / 3.0));

  SECTION("y is a period only between no side walls") {
    std::vector<core::Grain> across = before;
    across[2].position.y() = 0.0;  // 1.5 along y either way
    across[0].position.y() = 2.9;  // 1.9 between walls, 1.1 through a periodic y
    CHECK(analysis::displacement(box, before, across).max == Approx(1.9));
    box.periodicY = true;
    CHECK(analysis::displacement(box, before, across).max == Approx(1.5));
  }
  SECTION("grains at rest moved by nothing") {
    CHECK(analysis::displacement(box, before, before).max == 0.0);
  }
  SECTION("two lists of different grains are refused") {
    after.pop_back();
    CHECK_THROWS_AS(analysis::displacement(box, before, after), std::invalid_argument);
  }
}
