#include <catch2/catch.hpp>
#include <cmath>

#include "core/box.hpp"
#include "core/population.hpp"
#include "core/random.hpp"

using namespace confpack::core;

TEST_CASE("random streams are reproducible and independent") {
  Rng a(7, StreamId::Test), b(7, StreamId::Test), c(8, StreamId::Test), d(7, StreamId::GrainSizes);
  for (int i = 0; i < 100; ++i) {
    const auto x = a.next();
    CHECK(x == b.next());
    CHECK(x != c.next());
    CHECK(x != d.next());
  }
}

TEST_CASE("uniform draws have mean 1/2 and variance 1/12") {
  Rng r(3, StreamId::Test);
  const int n = 200000;
  double s = 0, s2 = 0;
  for (int i = 0; i < n; ++i) {
    const double u = r.uniform();
    REQUIRE(u >= 0.0);
    REQUIRE(u < 1.0);
    s += u;
    s2 += u * u;
  }
  const double mean = s / n, var = s2 / n - mean * mean;
  CHECK(mean == Approx(0.5).margin(5 * std::sqrt(1.0 / 12 / n)));
  CHECK(var == Approx(1.0 / 12).margin(2e-3));
}

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

TEST_CASE("orientations are uniform on SO(3): <R_ij> = 0, <R_ij^2> = 1/3") {
  Rng r(17, StreamId::Test);
  const int n = 60000;
  Mat3 m1 = Mat3::Zero(), m2 = Mat3::Zero();
  for (int i = 0; i < n; ++i) {
    const Mat3 R = r.uniformQuaternion().toRotationMatrix();
    m1 += R;
    m2 += R.cwiseProduct(R);
  }
  m1 /= n;
  m2 /= n;
  // Var(R_ij) = 1/3 for a Haar rotation; 5 standard errors.
  const double tol1 = 5 * std::sqrt(1.0 / 3.0 / n);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      CHECK(std::abs(m1(i, j)) < tol1);
      CHECK(m2(i, j) == Approx(1.0 / 3.0).margin(0.01));
    }
}

TEST_CASE("population validation names the bad field") {
  PopulationDef def;
  def.smallFraction = 120;
  CHECK_THROWS_WITH(def.validate(), Catch::Contains("small fraction"));
}

TEST_CASE("wrapping a tiny negative coordinate stays inside the period") {
  BoxDef box;
  box.lengthX = 20.0;
  box.periodicY = true;
  for (double x : {-1e-16, -1.7e-15, -0.0, 20.0, 40.0, -20.0}) {
    const Vec3 w = box.wrap(Vec3(x, x / 2, 1.0));
    CHECK(w.x() >= 0.0);
    CHECK(w.x() < box.lengthX);
    CHECK(w.y() >= 0.0);
    CHECK(w.y() < box.width);
  }
}
