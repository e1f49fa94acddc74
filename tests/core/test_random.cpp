// Rng (core/random.hpp): reproducible independent streams, uniform draws, Haar-uniform rotations.
#include <catch2/catch.hpp>
#include <cmath>

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
