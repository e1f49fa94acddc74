// Population (core/population.hpp): grain sizes, the bidisperse mixture and validation.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "core/population.hpp"
#include "core/random.hpp"

using namespace confpack::core;

TEST_CASE("sizes: truncated Gaussian with sigma = d/30 cut at 3 sigma") {
  Rng r(11, StreamId::Test);
  const int n = 100000;
  const double d = 0.5;
  double s = 0, s2 = 0, lo = 1e9, hi = -1e9;
  for (int i = 0; i < n; ++i) {
    const double x = drawSize(r, d, 1.0 / 30.0, 3.0);
    s += x;
    s2 += x * x;
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  const double mean = s / n, sd = std::sqrt(s2 / n - mean * mean);
  const double sigma = d / 30.0;
  CHECK(mean == Approx(d).margin(5 * sigma / std::sqrt(n)));
  // A Gaussian truncated at +-3 sigma has standard deviation 0.98658 sigma.
  CHECK(sd == Approx(0.98658 * sigma).epsilon(0.01));
  CHECK(lo >= d - 3 * sigma);
  CHECK(hi <= d + 3 * sigma);
  CHECK(lo < d - 2.5 * sigma);  // the tails are really populated
  CHECK(hi > d + 2.5 * sigma);
}

TEST_CASE("bidisperse mixture: small grains make x_S of the volume") {
  for (double xs : {0.0, 10.0, 25.0, 40.0, 100.0}) {
    PopulationDef def;
    def.smallFraction = xs;
    const double target = 5000.0;
    const auto grains = drawGrains(def, target, 5);
    double vs = 0, vl = 0;
    for (const auto& g : grains) (g.size < 0.75 ? vs : vl) += g.volume();
    CHECK(vs + vl == Approx(target).epsilon(1e-3));
    // Each population is within half a grain of its share.
    CHECK(100.0 * vs / (vs + vl) == Approx(xs).margin(0.05));
  }
}

TEST_CASE("population validation names the bad field") {
  PopulationDef def;
  def.smallFraction = 120;
  CHECK_THROWS_WITH(def.validate(), Catch::Contains("population.small_fraction: must be in [0, 100] (got 120)"));
}

// Sizes are drawn by rejection inside +-truncation_sigmas: with 0 or less no draw is ever
// accepted, so such a population would hang the deposit instead of being refused.
TEST_CASE("population validation refuses a truncation that no size draw can meet") {
  PopulationDef def;
  def.truncationSigmas = GENERATE(0.0, -1.0);
  CHECK_THROWS_WITH(def.validate(), Catch::StartsWith("population.truncation_sigmas: must be > 0"));
}

// A population of spheres carries pinacoid parameters it never uses: they are checked only when
// the shape is pinacoid (a sweep over alpha may share a spec with sphere families).
TEST_CASE("population validation checks the pinacoid's shape only for pinacoids") {
  PopulationDef def;
  def.pinacoid.alphaDeg = 45.0;  // with E = L the ridge vanishes: not a pinacoid
  def.pinacoid.heightRatio = 1.0;
  CHECK_NOTHROW(def.validate());
  def.shape = ShapeKind::Pinacoid;
  CHECK_THROWS_WITH(def.validate(), Catch::Contains("ridge half-length"));
}
