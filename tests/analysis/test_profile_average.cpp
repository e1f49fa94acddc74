// The fit of a seed-averaged phi(y) profile (analysis/profile_average.hpp): synthetic profiles of
// known lambda_L and lambda_S, each "seed" with its own noise correlated over a fifth of a grain
// (as a packing's slices are), averaged over three seeds: lambda is recovered within its stated
// uncertainty, that uncertainty is of the size of the fits' real scatter, and the fit ends in
// the same minimum whichever seed's data it starts from.
#include <catch2/catch.hpp>
#include <cmath>

#include "analysis/profile_average.hpp"
#include "core/random.hpp"

using namespace confpack;

namespace {

constexpr double kSlice = 0.02;  // d_L, as a run's profile
constexpr int kSlices = 250;     // 5 d_L: half of W = 10

// A bidisperse layering: large grains' period 0.95 d_L decaying over 1.2 d_L, small grains'
// 0.47 d_L over 0.5 d_L.
analysis::ProfileLaw twoSpecies() {
  analysis::ProfileLaw law;
  law.bidisperse = true;
  law.alpha = 0.08;
  law.phiBulk = 0.66;
  law.beta[0] = 0.2;
  law.gamma[0] = 0.95;
  law.lambda[0] = 1.2;
  law.beta[1] = 0.06;
  law.gamma[1] = 0.47;
  law.lambda[1] = 0.5;
  return law;
}

// One seed's profile: the law plus white noise smoothed over `width` slices, of standard deviation
// `noise` after smoothing.
analysis::SeedProfile seedProfile(const analysis::ProfileLaw& law, double noise, int width, core::Rng& rng) {
  std::vector<double> white(kSlices + width);
  for (double& v : white) v = rng.normal();
  analysis::SeedProfile p;
  p.meanSize = law.bidisperse ? 0.62 : 1.0;
  for (int k = 0; k < kSlices; ++k) {
    double s = 0.0;
    for (int j = 0; j < width; ++j) s += white[k + j];
    const double y = (k + 0.5) * kSlice;
    p.y.push_back(y);
    p.phi.push_back(law(y) + noise * s / std::sqrt(static_cast<double>(width)));
  }
  return p;
}

std::vector<analysis::SeedProfile> seeds(const analysis::ProfileLaw& law, double noise, std::uint64_t seed, int n = 3) {
  core::Rng rng(seed, core::StreamId::Test);
  std::vector<analysis::SeedProfile> out;
  for (int i = 0; i < n; ++i) out.push_back(seedProfile(law, noise, 10, rng));
  return out;
}

}  // namespace

TEST_CASE("seed-averaged phi(y) fit recovers lambda_L and lambda_S within the stated uncertainty", "[analysis][fit]") {
  const analysis::ProfileLaw truth = twoSpecies();
  analysis::ProfileFitDef def;
  def.bidisperse = true;

  // Over 24 independent studies of 3 seeds: the fit lands within 2 sigma of the truth as often as
  // a Gaussian error would (95 %; 20 of 24 allows for the jackknife's few degrees of freedom), and
  // sigma is the size of the scatter of the fitted values, neither far below (overconfident) nor
  // far above (useless).
  constexpr int studies = 24;
  int within = 0, withinS = 0, determinedS = 0;
  double sumL = 0.0, sumL2 = 0.0, sumSigma = 0.0;
  for (int k = 0; k < studies; ++k) {
    const auto f = analysis::fitAveragedProfile(seeds(truth, 0.012, 100 + k), def);
    REQUIRE(f.ok);
    REQUIRE(f.seeds == 3);
    REQUIRE(f.lambdaL.determined);
    REQUIRE(f.lambdaL.jackknifeError);
    CHECK(f.lambdaL.error >= f.lambdaL.covarianceError);
    CHECK(f.lambdaL.error >= *f.lambdaL.jackknifeError);
    if (std::abs(f.lambdaL.value - truth.lambda[0]) < 2.0 * f.lambdaL.error) ++within;
    if (f.lambdaS.determined) {
      ++determinedS;
      if (std::abs(f.lambdaS.value - truth.lambda[1]) < 2.0 * f.lambdaS.error) ++withinS;
    }
    sumL += f.lambdaL.value;
    sumL2 += f.lambdaL.value * f.lambdaL.value;
    sumSigma += f.lambdaL.error;
    // lambda_L / d_avg carries the same relative error.
    CHECK(f.lambdaLOverDAvg.value == Approx(f.lambdaL.value / 0.62));
    CHECK(f.lambdaLOverDAvg.error == Approx(f.lambdaL.error / 0.62));
  }
  const double mean = sumL / studies;
  const double scatter = std::sqrt((sumL2 - studies * mean * mean) / (studies - 1));
  const double sigma = sumSigma / studies;
  INFO("lambda_L: mean " << mean << ", scatter " << scatter << ", mean sigma " << sigma);
  CHECK(within >= 20);
  CHECK(determinedS >= 20);
  CHECK(withinS >= determinedS - 4);
  CHECK(std::abs(mean - truth.lambda[0]) < 3.0 * scatter / std::sqrt(studies));  // no bias beyond the noise
  CHECK(sigma > 0.6 * scatter);
  CHECK(sigma < 2.5 * scatter);
  // Determined to better than a third of itself, as the medium study's spheres must be.
  CHECK(sigma < truth.lambda[0] / 3.0);
}

TEST_CASE("seed-averaged phi(y) fit ends in one minimum from any seed's starting values", "[analysis][fit]") {
  const analysis::ProfileLaw truth = twoSpecies();
  const auto data = seeds(truth, 0.012, 7);
  analysis::ProfileFitDef def;
  def.bidisperse = true;
  const auto averaged = analysis::fitAveragedProfile(data, def);
  REQUIRE(averaged.ok);
  // The mean profile fitted from the starting values each seed's own profile gives (its peaks,
  // its tail), and from starts far off on either side: the same parameters.
  std::vector<analysis::ProfileLaw> starts;
  for (const auto& s : data) starts.push_back(analysis::initialGuess(s.y, s.phi, true));
  analysis::ProfileLaw far = truth;
  far.lambda[0] = 4.0;
  far.lambda[1] = 2.0;
  far.alpha = 0.3;
  starts.push_back(far);
  far.lambda[0] = 0.3;
  far.lambda[1] = 0.1;
  far.alpha = 0.02;
  starts.push_back(far);
  for (const auto& start : starts) {
    analysis::ProfileFitDef from = def;
    from.start = start;
    const auto f = analysis::fitProfile(averaged.y, averaged.phi, from);
    REQUIRE(f.ok);
    CHECK(f.law.lambda[0] == Approx(averaged.fit.law.lambda[0]).epsilon(1e-4));
    CHECK(f.law.lambda[1] == Approx(averaged.fit.law.lambda[1]).epsilon(1e-4));
    CHECK(f.chiSquare == Approx(averaged.fit.chiSquare).epsilon(1e-8));
  }
  // Each seed's profile alone, bounded, stays in the same basin: its lambda_L is the averaged
  // fit's within the seeds' scatter (sqrt(3) x the mean's uncertainty), not a runaway.
  for (const auto& s : data) {
    const auto f = analysis::fitProfile(s.y, s.phi, def);
    REQUIRE(f.ok);
    CHECK(std::abs(f.law.lambda[0] - averaged.lambdaL.value) < 3.0 * std::sqrt(3.0) * averaged.lambdaL.error);
  }
}

TEST_CASE("seed-averaged phi(y) fit: monodisperse, one seed, and profiles on other grids", "[analysis][fit]") {
  analysis::ProfileLaw mono = twoSpecies();
  mono.bidisperse = false;
  mono.beta[1] = 0.0;
  const auto f = analysis::fitAveragedProfile(seeds(mono, 0.012, 11));
  REQUIRE(f.ok);
  CHECK_FALSE(f.lambdaS.determined);
  CHECK(std::abs(f.lambdaL.value - mono.lambda[0]) < 3.0 * f.lambdaL.error);
  CHECK(f.leaveOneOutLambdaL.size() == 3);

  // One seed: no jackknife, the covariance alone.
  const auto one = analysis::fitAveragedProfile(seeds(mono, 0.012, 12, 1));
  REQUIRE(one.ok);
  CHECK_FALSE(one.lambdaL.jackknifeError);
  CHECK(one.lambdaL.error == one.lambdaL.covarianceError);

  auto other = seeds(mono, 0.012, 13);
  other[1].y[5] += 0.001;
  CHECK_THROWS_AS(analysis::fitAveragedProfile(other), std::invalid_argument);
  CHECK_FALSE(analysis::fitAveragedProfile({}).ok);
}
