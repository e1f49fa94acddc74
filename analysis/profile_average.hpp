#pragma once
// The fit of a seed-averaged phi(y) profile (docs/model.md, "Solid-fraction profiles and their
// fit", "The seed-averaged fit"): the profiles of a configuration's replicas (seeds), on one
// grid, are averaged slice by slice and the mean profile is fitted with the law of
// analysis/profile_fit.hpp. One seed's profile is too noisy to fix a decay length (the layering
// beyond the second layer is of the size of the packing's own fluctuations); the mean of n seeds
// has sqrt(n) less of that noise and one minimum.
//
// Uncertainty of a parameter p, two estimates, the larger kept:
// - covariance: the standard error of the mean profile's fit, (J^T J)^-1 chi^2/dof. It takes the
//   residuals as independent, which slices d_L/50 thin are not (a grain spans fifty of them), so
//   on its own it is too small;
// - jackknife over the seeds: the mean profile without seed i is fitted, starting from the full
//   fit (the same minimum), giving p_(i); sigma_jk^2 = (n-1)/n sum_i (p_(i) - p_(.))^2 (Efron &
//   Tibshirani 1993, ch. 11). It measures how much the fit moves with the seeds, the scatter the
//   replicas really have, whatever the correlation of the residuals.
// With fewer than 2 seeds, or when a leave-one-out fit fails, there is no jackknife and the
// covariance alone is given (and said so: jackknifeError is empty).
#include <optional>
#include <string>
#include <vector>

#include "analysis/profile_fit.hpp"

namespace confpack::analysis {

/// One replica's folded profile and its mean grain size.
struct SeedProfile {
  std::vector<double> y;    ///< distance from the wall [d_L], ascending
  std::vector<double> phi;  ///< solid fraction of each slice
  double meanSize = 1.0;    ///< d_avg: the number mean of the grains' sizes [d_L]
};

/// A fitted length with its uncertainty.
struct FittedLength {
  bool determined = false;  ///< false: the data do not fix it (see the fit's reason or note)
  double value = 0.0;
  double error = 0.0;                    ///< max(covarianceError, jackknifeError)
  double covarianceError = 0.0;          ///< of the mean profile's fit
  std::optional<double> jackknifeError;  ///< over the seeds; none with < 2 seeds or a failed leave-one-out fit
};

struct AveragedProfileFit {
  bool ok = false;
  std::string reason;                      ///< why not ok
  int seeds = 0;                           ///< profiles averaged
  std::vector<double> y, phi;              ///< the mean profile
  ProfileFit fit;                          ///< of the mean profile
  double meanSize = 0.0;                   ///< d_avg, mean over the seeds [d_L]
  FittedLength lambdaL;                    ///< [d_L]
  FittedLength lambdaS;                    ///< [d_L]; bidisperse fits only
  FittedLength lambdaLOverDAvg;            ///< lambda_L / d_avg [-]
  std::vector<double> leaveOneOutLambdaL;  ///< lambda_L of the fit without seed i
};

/// Averages `seeds` (they must share the grid: same y to 1e-9 d_L; std::invalid_argument
/// otherwise) and fits the mean profile with `def`, then each leave-one-out mean from the full
/// fit's parameters. Does not throw on a failed fit (ok = false with the reason).
AveragedProfileFit fitAveragedProfile(const std::vector<SeedProfile>& seeds, const ProfileFitDef& def = {});

}  // namespace confpack::analysis
