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

TEST_CASE("nematic order: n random orientations give about 1/sqrt(n), the floor of a finite sample",
          "[analysis][nematic]") {
  // The largest eigenvalue of a sum of n random traceless tensors, the largest of three: no
  // sample of n grains reads as unordered below it (docs/pinacoids-and-the-paper.md, "The nematic
  // order and the size of the sample"). Mean over 100 samples; its standard error is under 3 %.
  core::Rng rng(5, core::StreamId::Test);
  for (int n : {40, 1000}) {
    double sum = 0.0;
    constexpr int kSamples = 100;
    for (int sample = 0; sample < kSamples; ++sample) {
      std::vector<core::Mat3> random;
      for (int k = 0; k < n; ++k) random.push_back(rng.uniformQuaternion().toRotationMatrix());
      sum += analysis::nematicOrder(random).q00;
    }
    const double scaled = sum / kSamples * std::sqrt(double(n));
    INFO("n = " << n << ": mean Q00^2 sqrt(n) = " << scaled);
    CHECK(scaled > 0.9);
    CHECK(scaled < 1.2);
  }
}
