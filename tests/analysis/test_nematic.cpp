// Nematic order (analysis/nematic.hpp; docs/model.md, "Order") of aligned and random pinacoids.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/bulk_region.hpp"
#include "analysis/nematic.hpp"
#include "core/random.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;
using confpack::testing::simpleCubic;

TEST_CASE("nematic order: aligned and random pinacoids", "[analysis][nematic]") {
  std::vector<core::Mat3> aligned(
      50, core::Quat(Eigen::AngleAxisd(0.4, core::Vec3(1, 2, 3).normalized())).toRotationMatrix());
  const auto a = analysis::nematicOrder(aligned);
  CHECK(a.q00 == Approx(1.0));
  core::Rng rng(11, core::StreamId::Test);
  for (int n : {400, 6400}) {
    std::vector<core::Mat3> random;
    for (int k = 0; k < n; ++k) random.push_back(rng.uniformQuaternion().toRotationMatrix());
    const auto r = analysis::nematicOrder(random);
    CHECK(r.q00 > 0.0);
    CHECK(r.q00 < 4.0 / std::sqrt(double(n)));
  }
  // In a packing: boundary layers (within 2 d_L of a wall) and bulk are separate groups.
  core::Packing p;
  p.box.lengthX = 10;
  p.box.width = 10;
  for (int k = 0; k < 20; ++k) {
    core::Grain g;
    g.shape = core::ShapeKind::Pinacoid;
    g.position = core::Vec3(0.5 * k, k % 2 ? 1.0 : 5.0, 5.0);
    g.orientation = k % 2 ? core::Quat::Identity() : rng.uniformQuaternion();
    p.grains.push_back(g);
  }
  const auto nem = analysis::nematic(p, analysis::BulkRegion{10, 3, 7});
  REQUIRE(nem.boundary.has_value());
  REQUIRE(nem.bulk.has_value());
  CHECK(nem.boundary->q00 == Approx(1.0));
  CHECK(nem.boundary->grains == 10);
  CHECK(nem.bulk->q00 < 0.9);
  CHECK_FALSE(analysis::nematic(simpleCubic(3, 3, 8), analysis::BulkRegion{8, 3, 5}).bulk.has_value());
}
