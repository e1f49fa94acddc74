// The nonlinear phi(y) law (analysis/profile_fit.hpp; docs/model.md, "Solid-fraction profiles and
// their fit") fitted to synthetic profiles: known parameters recovered with honest uncertainties.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <new>
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

// AddressSanitizer reserves terabytes of address space for its shadow: an address-space limit
// cannot be set under it (.ci/sanitize).
#if !defined(__SANITIZE_ADDRESS__)
TEST_CASE("phi(y) fit: a GSL allocation that fails is std::bad_alloc, not a crash inside GSL", "[analysis][fit]") {
  // The failure this guards against: the NULL of a failed gsl_multifit_nlinear_alloc went on into
  // gsl_multifit_nlinear_winit (SIGSEGV). In a child, a long bidisperse profile is fitted under an
  // address-space limit that leaves room for fitProfile's copies of the data but not for GSL's
  // workspace (its Jacobian alone is 8 doubles a point): it must throw std::bad_alloc (exit 0
  // here), and neither crash nor fit.
  constexpr std::size_t n = 2'000'000;
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const analysis::ProfileLaw law = layered(0.8);
    std::vector<double> y(n), phi(n);
    for (std::size_t k = 0; k < n; ++k) {
      y[k] = (static_cast<double>(k) + 0.5) * 1e-5;
      phi[k] = law(y[k]);
    }
    analysis::ProfileFitDef def;
    def.bidisperse = true;
    std::size_t pages = 0;
    std::ifstream("/proc/self/statm") >> pages;
    const rlim_t room = pages * static_cast<rlim_t>(::sysconf(_SC_PAGESIZE)) + 6 * n * sizeof(double) + (32 << 20);
    const rlimit limit{room, room};
    if (::setrlimit(RLIMIT_AS, &limit) != 0) _exit(5);
    try {
      (void)analysis::fitProfile(y, phi, def);
      _exit(3);  // the workspace fitted after all: the limit let too much through
    } catch (const std::bad_alloc&) {
      _exit(0);
    } catch (...) {
      _exit(4);
    }
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  INFO("status " << status);
  REQUIRE(WIFEXITED(status));  // not killed by SIGSEGV
  CHECK(WEXITSTATUS(status) == 0);
}
#endif
