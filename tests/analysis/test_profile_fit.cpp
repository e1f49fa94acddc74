// The nonlinear phi(y) law (analysis/profile_fit.hpp; docs/model.md, "Solid-fraction profiles and
// their fit") fitted to synthetic profiles: known parameters recovered with honest uncertainties.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/profile_fit.hpp"
#include "core/random.hpp"

using namespace confpack;

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
/// A monodisperse layering near a wall, decaying over lambdaL [d_L].
analysis::ProfileLaw layered(double lambdaL) {
  analysis::ProfileLaw law;
  law.alpha = 0.08;
  law.phiBulk = 0.61;
  law.beta[0] = 0.2;
  law.gamma[0] = 0.92;
  law.lambda[0] = lambdaL;
  return law;
}
}  // namespace

TEST_CASE("nonlinear phi(y) fit recovers known parameters with honest errors", "[analysis][fit]") {
  const analysis::ProfileLaw truth = layered(0.8);

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

TEST_CASE("phi(y) fit: a layering that does not decay within the profile gives no decay length", "[analysis][fit]") {
  // Undamped layering over 5 d_L: the law's lambda is not determined by these data (the fit lets it
  // run far beyond them); a decay within the data is still measured.
  const auto undamped = synthetic(layered(1e6), 0.002, 4);
  const auto f = analysis::fitProfile(undamped.y, undamped.phi);
  CHECK_FALSE(f.ok);
  CHECK_THAT(f.reason, Catch::Contains("does not decay within the profile"));

  // 2 d_L: the amplitude falls by e^2.5 across the 5 d_L of data.
  const auto damped = synthetic(layered(2.0), 0.002, 4);
  const auto g = analysis::fitProfile(damped.y, damped.phi);
  REQUIRE(g.ok);
  CHECK(std::abs(g.law.lambda[0] - 2.0) < 4 * g.error.lambda[0]);
}
