#pragma once
// The geometrical model and the linear fits across a study (docs/model.md, "The geometrical
// model", "Solid-fraction profiles and their fit", "Coordination number").
//
//   phi(W) = phi_bulk - C / W,   C = 2 h (phi_bulk - phi_BL)
// is a straight line in x = 1/W: intercept phi_bulk, slope -C. It is fitted by (weighted) linear
// least squares with GSL (gsl_fit_wlinear with weights 1/sigma^2 when the points carry standard
// errors, e.g. from replicas; gsl_fit_linear otherwise, whose covariance is then estimated from
// the scatter, chi^2/(n-2)). Quality of fit: Q = P(chi^2 > observed | n-2 dof)
// (gsl_cdf_chisq_Q), defined only for weighted fits with n > 2.
// The same fit gives Z(W) = Z_bulk - C_Z / W; zeta = C / intercept (zeta_phi, zeta_Z).
// Cross-check of C: 2 x integral over the half profile of (phi_bulk - phi(y)) dy.
// lambda_L against C: a straight line through the origin (gsl_fit_mul / gsl_fit_wmul), or with an
// intercept (fitLine).
#include <optional>
#include <vector>

#include "analysis/solid_fraction.hpp"

namespace confpack::analysis {

struct ConfinementFit {
  double bulk = 0.0;              ///< intercept: phi_bulk (or Z_bulk) [-]
  double c = 0.0;                 ///< C = -slope [d_L]
  double bulkError = 0.0;         ///< standard error of the intercept
  double cError = 0.0;            ///< standard error of C
  double covariance = 0.0;        ///< cov(bulk, C)
  double chiSquare = 0.0;         ///< weighted: sum ((y - fit)/sigma)^2; unweighted: sum of squared residuals
  int dof = 0;                    ///< n - 2
  std::optional<double> quality;  ///< Q of the chi^2 (weighted fits with dof > 0)
  bool weighted = false;
  double zeta() const { return bulk != 0.0 ? c / bulk : 0.0; }  ///< C / bulk [d_L]
};

/// Fits value(W) = bulk - C / W. sigma empty = unweighted. Throws std::invalid_argument for fewer
/// than 2 points, sizes that differ, a non-positive width or a non-positive sigma.
ConfinementFit fitConfinement(const std::vector<double>& width, const std::vector<double>& value,
                              const std::vector<double>& sigma = {});

struct ProportionalFit {
  double slope = 0.0;
  double slopeError = 0.0;
  double chiSquare = 0.0;
  int dof = 0;
};

/// Fits y = slope * x through the origin (e.g. lambda_L against C). sigma empty = unweighted.
ProportionalFit fitThroughOrigin(const std::vector<double>& x, const std::vector<double>& y,
                                 const std::vector<double>& sigma = {});

struct LineFit {
  double intercept = 0.0, slope = 0.0;
  double interceptError = 0.0, slopeError = 0.0;
  double covariance = 0.0;        ///< cov(intercept, slope)
  double chiSquare = 0.0;         ///< weighted: sum ((y - fit)/sigma)^2; unweighted: sum of squared residuals
  int dof = 0;                    ///< n - 2
  std::optional<double> quality;  ///< Q of the chi^2 (weighted fits with dof > 0)
  bool weighted = false;
  double correlation = 0.0;  ///< Pearson's r of the points, unweighted; 0 where y does not vary
};

/// Fits y = intercept + slope x (e.g. lambda_L / d_avg against x_S), weighted by 1/sigma^2
/// (gsl_fit_wlinear), or unweighted with the covariance from the scatter when sigma is empty.
/// Throws std::invalid_argument for fewer than 2 points, sizes that differ, a non-positive sigma
/// or all points at one x.
LineFit fitLine(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& sigma = {});

/// C from a folded wall-normal profile: 2 sum_k (phi_bulk - phi_k) dy over y in [0, W/2] [d_L].
double profileIntegralC(const SolidFractionProfile& profile, double phiBulk);

}  // namespace confpack::analysis
