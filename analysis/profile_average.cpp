#include "analysis/profile_average.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace confpack::analysis {

namespace {

// Slice-by-slice mean of the profiles of `seeds` except `skip` (none: all).
std::vector<double> meanProfile(const std::vector<SeedProfile>& seeds, std::optional<std::size_t> skip) {
  std::vector<double> mean(seeds.front().phi.size(), 0.0);
  double n = 0.0;
  for (std::size_t s = 0; s < seeds.size(); ++s) {
    if (skip && *skip == s) continue;
    for (std::size_t k = 0; k < mean.size(); ++k) mean[k] += seeds[s].phi[k];
    n += 1.0;
  }
  for (double& v : mean) v /= n;
  return mean;
}

void checkGrid(const std::vector<SeedProfile>& seeds) {
  const SeedProfile& first = seeds.front();
  for (std::size_t s = 0; s < seeds.size(); ++s) {
    const SeedProfile& p = seeds[s];
    if (p.y.size() != p.phi.size())
      throw std::invalid_argument(
          fmt::format("averaged profile fit: seed {} has {} positions for {} values", s, p.y.size(), p.phi.size()));
    bool same = p.y.size() == first.y.size();
    for (std::size_t k = 0; same && k < p.y.size(); ++k) same = std::abs(p.y[k] - first.y[k]) < 1e-9;
    if (!same)
      throw std::invalid_argument(
          fmt::format("averaged profile fit: seed {}'s profile is on another grid than seed 0's ({} and {} slices)", s,
                      p.y.size(), first.y.size()));
  }
}

}  // namespace

AveragedProfileFit fitAveragedProfile(const std::vector<SeedProfile>& seeds, const ProfileFitDef& def) {
  AveragedProfileFit out;
  out.seeds = static_cast<int>(seeds.size());
  if (seeds.empty()) {
    out.reason = "no profile";
    return out;
  }
  checkGrid(seeds);
  out.y = seeds.front().y;
  out.phi = meanProfile(seeds, std::nullopt);
  for (const SeedProfile& s : seeds) out.meanSize += s.meanSize;
  out.meanSize /= static_cast<double>(seeds.size());
  out.fit = fitProfile(out.y, out.phi, def);
  if (!out.fit.ok) {
    out.reason = out.fit.reason;
    return out;
  }
  out.ok = true;

  // Jackknife: each leave-one-out mean fitted from the full fit, so that it stays in its basin. A
  // length a leave-one-out fit does not determine has no jackknife error.
  const int lengths = def.bidisperse ? 2 : 1;
  std::vector<std::vector<double>> loo(lengths);
  bool jackknife = seeds.size() >= 2;
  bool usable[2] = {jackknife, jackknife};
  if (jackknife) {
    ProfileFitDef from = def;
    from.start = out.fit.law;
    for (std::size_t s = 0; s < seeds.size(); ++s) {
      const ProfileFit f = fitProfile(out.y, meanProfile(seeds, s), from);
      for (int i = 0; i < lengths; ++i) {
        usable[i] = usable[i] && f.ok && f.lambdaDetermined[i];
        loo[i].push_back(f.law.lambda[i]);
      }
    }
  }
  const auto jackknifeError = [&](int i) -> std::optional<double> {
    if (!usable[i]) return std::nullopt;
    const double n = static_cast<double>(loo[i].size());
    double mean = 0.0, sum = 0.0;
    for (double v : loo[i]) mean += v / n;
    for (double v : loo[i]) sum += (v - mean) * (v - mean);
    return std::sqrt((n - 1.0) / n * sum);
  };
  if (usable[0]) out.leaveOneOutLambdaL = loo[0];
  for (int i = 0; i < lengths; ++i) {
    FittedLength& l = i == 0 ? out.lambdaL : out.lambdaS;
    l.determined = out.fit.lambdaDetermined[i];
    l.value = out.fit.law.lambda[i];
    l.covarianceError = out.fit.error.lambda[i];
    l.jackknifeError = l.determined ? jackknifeError(i) : std::nullopt;
    l.error = std::max(l.covarianceError, l.jackknifeError.value_or(0.0));
  }
  out.lambdaLOverDAvg = out.lambdaL;
  const double d = out.meanSize > 0.0 ? out.meanSize : 1.0;
  out.lambdaLOverDAvg.value /= d;
  out.lambdaLOverDAvg.error /= d;
  out.lambdaLOverDAvg.covarianceError /= d;
  if (out.lambdaLOverDAvg.jackknifeError) *out.lambdaLOverDAvg.jackknifeError /= d;
  return out;
}

}  // namespace confpack::analysis
