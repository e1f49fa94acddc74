// The geometrical model (analysis/geometric_model.hpp; docs/model.md, "The geometrical model"): the
// GSL fits phi(W) = phi_bulk - C/W and through the origin, and the profile-integral C, recovering
// known parameters.
#include <catch2/catch.hpp>
#include <cmath>

#include "analysis/geometric_model.hpp"
#include "core/random.hpp"

using namespace confpack;

TEST_CASE("phi(W) linear fit recovers phi_bulk and C", "[analysis][fit]") {
  const std::vector<double> width{4, 5, 10, 20};
  std::vector<double> phi;
  for (double w : width) phi.push_back(0.64 - 0.15 / w);
  const auto exact = analysis::fitConfinement(width, phi);
  CHECK(exact.bulk == Approx(0.64).epsilon(1e-12));
  CHECK(exact.c == Approx(0.15).epsilon(1e-10));
  CHECK(exact.zeta() == Approx(0.15 / 0.64).epsilon(1e-10));
  CHECK_FALSE(exact.quality.has_value());

  // Noisy replicas with known sigma: estimates within 3 standard errors, sensible quality.
  core::Rng rng(5, core::StreamId::Test);
  const double sigma = 0.002;
  int within = 0;
  const int trials = 40;
  for (int t = 0; t < trials; ++t) {
    std::vector<double> noisy;
    for (double v : phi) noisy.push_back(v + sigma * rng.normal());
    const auto f = analysis::fitConfinement(width, noisy, std::vector<double>(width.size(), sigma));
    REQUIRE(f.quality.has_value());
    CHECK(*f.quality >= 0.0);
    CHECK(*f.quality <= 1.0);
    within += std::abs(f.bulk - 0.64) < 3 * f.bulkError && std::abs(f.c - 0.15) < 3 * f.cError;
  }
  CHECK(within >= trials - 2);
  // Standard error of the intercept for these abscissae, from the normal equations.
  const auto f = analysis::fitConfinement(width, phi, std::vector<double>(width.size(), sigma));
  double s = 0, sx = 0, sxx = 0;
  for (double w : width) {
    s += 1 / (sigma * sigma);
    sx += (1 / w) / (sigma * sigma);
    sxx += (1 / (w * w)) / (sigma * sigma);
  }
  CHECK(f.bulkError == Approx(std::sqrt(sxx / (s * sxx - sx * sx))));
  CHECK(f.cError == Approx(std::sqrt(s / (s * sxx - sx * sx))));

  CHECK_THROWS_AS(analysis::fitConfinement({4.0}, {0.6}), std::invalid_argument);
  CHECK_THROWS_AS(analysis::fitConfinement({4.0, 0.0}, {0.6, 0.6}), std::invalid_argument);
  CHECK_THROWS_AS(analysis::fitConfinement({4.0, 5.0}, {0.6, 0.6}, {0.1, -1.0}), std::invalid_argument);
}

TEST_CASE("fit through the origin and the profile-integral C", "[analysis][fit]") {
  const auto f = analysis::fitThroughOrigin({0.1, 0.2, 0.3}, {0.25, 0.5, 0.75});
  CHECK(f.slope == Approx(2.5));
  CHECK(f.slopeError == Approx(0.0).margin(1e-12));
  // A two-layer profile: phi_BL over h = 0.6 from the wall, phi_bulk beyond: C = 2 h (phi_b - phi_BL).
  analysis::SolidFractionProfile p;
  p.slice = 0.02;
  p.folded = true;
  for (int k = 0; k < 250; ++k) {
    p.y.push_back((k + 0.5) * 0.02);
    p.phi.push_back(k < 30 ? 0.5 : 0.64);
  }
  CHECK(analysis::profileIntegralC(p, 0.64) == Approx(2 * 0.6 * 0.14));
}

TEST_CASE("line fit recovers intercept, slope and Pearson's r", "[analysis][fit]") {
  const std::vector<double> x{0.0, 10.0, 25.0, 40.0};
  std::vector<double> y;
  for (double v : x) y.push_back(1.5 - 0.02 * v);
  const analysis::LineFit exact = analysis::fitLine(x, y);
  CHECK(exact.intercept == Approx(1.5).epsilon(1e-12));
  CHECK(exact.slope == Approx(-0.02).epsilon(1e-10));
  CHECK(exact.correlation == Approx(-1.0).epsilon(1e-12));  // every point on a falling line
  // Weighted, with points scattered by +-sigma: the chi^2 is the scatter's, r below 1 in size.
  const std::vector<double> noisy{1.6, 1.2, 1.1, 0.6}, sigma{0.1, 0.1, 0.1, 0.1};
  const analysis::LineFit w = analysis::fitLine(x, noisy, sigma);
  CHECK(w.weighted);
  CHECK(w.quality.has_value());
  CHECK(w.slope < 0.0);
  CHECK(w.correlation < -0.9);
  CHECK(w.correlation > -1.0);
  // A flat line has no correlation to speak of.
  CHECK(analysis::fitLine(x, {1.0, 1.0, 1.0, 1.0}).correlation == 0.0);
  CHECK_THROWS_AS(analysis::fitLine({2.0, 2.0}, {1.0, 3.0}), std::invalid_argument);
}
