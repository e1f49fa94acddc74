// GSL fits: phi(W) = phi_bulk - C/W, proportional fits, and the nonlinear phi(y) law
// (docs/model.md, "Solid-fraction profiles and their fit") recovering known parameters with honest
// uncertainties.
#include <catch2/catch.hpp>
#include <cmath>

#include "analysis/geometric_model.hpp"
#include "analysis/profile_fit.hpp"
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

namespace {
struct Synthetic {
  std::vector<double> y, phi;
};
Synthetic synthetic(const analysis::ProfileLaw& law, double noise, std::uint64_t seed) {
  core::Rng rng(seed, core::StreamId::Test);
  Synthetic s;
  for (int k = 0; k < 250; ++k) {
    const double y = (k + 0.5) * 0.02;
    s.y.push_back(y);
    s.phi.push_back(law(y) + noise * rng.normal());
  }
  return s;
}
}  // namespace

TEST_CASE("nonlinear phi(y) fit recovers known parameters with honest errors", "[analysis][fit]") {
  analysis::ProfileLaw truth;
  truth.alpha = 0.08;
  truth.phiBulk = 0.61;
  truth.beta[0] = 0.2;
  truth.gamma[0] = 0.92;
  truth.lambda[0] = 0.8;

  const auto clean = synthetic(truth, 0.0, 1);
  const auto exact = analysis::fitProfile(clean.y, clean.phi);
  REQUIRE(exact.ok);
  CHECK(exact.law.lambda[0] == Approx(truth.lambda[0]).epsilon(1e-6));
  CHECK(exact.law.gamma[0] == Approx(truth.gamma[0]).epsilon(1e-6));

  double previousError = 0.0;
  for (double noise : {0.004, 0.008}) {
    const auto data = synthetic(truth, noise, 2);
    const auto f = analysis::fitProfile(data.y, data.phi);
    REQUIRE(f.ok);
    CHECK(f.rms == Approx(noise).epsilon(0.15));
    CHECK(std::abs(f.law.alpha - truth.alpha) < 3.5 * f.error.alpha);
    CHECK(std::abs(f.law.phiBulk - truth.phiBulk) < 3.5 * f.error.phiBulk);
    CHECK(std::abs(f.law.beta[0] - truth.beta[0]) < 3.5 * f.error.beta[0]);
    CHECK(std::abs(f.law.gamma[0] - truth.gamma[0]) < 3.5 * f.error.gamma[0]);
    CHECK(std::abs(f.law.lambda[0] - truth.lambda[0]) < 3.5 * f.error.lambda[0]);
    // Standard errors scale like the noise.
    if (previousError > 0.0) CHECK(f.error.lambda[0] / previousError == Approx(2.0).epsilon(0.3));
    previousError = f.error.lambda[0];
  }

  SECTION("bidisperse law") {
    analysis::ProfileLaw bi = truth;
    bi.bidisperse = true;
    bi.beta[1] = 0.05;
    bi.gamma[1] = 0.47;
    bi.lambda[1] = 0.4;
    const auto data = synthetic(bi, 0.002, 3);
    analysis::ProfileFitDef def;
    def.bidisperse = true;
    const auto f = analysis::fitProfile(data.y, data.phi, def);
    REQUIRE(f.ok);
    CHECK(std::abs(f.law.lambda[0] - bi.lambda[0]) < 4 * f.error.lambda[0]);
    CHECK(std::abs(f.law.phiBulk - bi.phiBulk) < 4 * f.error.phiBulk);
  }

  SECTION("a flat or tiny profile is reported, not thrown") {
    const auto few = analysis::fitProfile({0.1, 0.2}, {0.5, 0.5});
    CHECK_FALSE(few.ok);
    CHECK_FALSE(few.reason.empty());
    CHECK_THROWS_AS(analysis::fitProfile({0.1, 0.2}, {0.5}), std::invalid_argument);
  }
}
