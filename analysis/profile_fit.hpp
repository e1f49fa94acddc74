#pragma once
// Nonlinear fit of the wall-normal solid-fraction profile (docs/model.md,
// "Solid-fraction profiles and their fit"):
//
//   phi(y) = [1 - exp(-y/alpha)] x [ phi_bulk + sum_{i in {S,L}} beta_i cos(pi (2y - 1)/gamma_i) exp(-y/lambda_i) ]
//
// (y in d_L from the wall; monodisperse: beta_S = 0 and the S term is dropped, 5 parameters;
// bidisperse: 8). GSL's gsl_multifit_nlinear, trust region with Levenberg-Marquardt steps and
// the analytic Jacobian. The profile has no per-point errors, so the covariance (J^T J)^-1 is
// scaled by chi^2/dof (the residual variance): the standard errors then describe the scatter of
// the data around the law.
//
// Initial guesses from the data (the fit does not converge to the layering from a blind start):
// phi_bulk = mean of the profile over its last d_L (one layering period); gamma_L = distance
// between the first two maxima of the profile (default 0.9 d_L when there are not two);
// lambda_L = gamma / ln((p1 - phi_b)/(p2 - phi_b)) from the first two peak heights (default 1);
// beta_L = (p1 - phi_b) exp(y1/lambda_L); alpha = 0.1. Small grains start at half the large
// grains' gamma and lambda and a tenth of beta. A few starts around these (alpha x {1, 0.5, 2},
// lambda x {1, 0.5, 2}) are run and the lowest chi^2 with positive alpha, gamma, lambda is kept.
#include <optional>
#include <string>
#include <vector>

namespace confpack::analysis {

/// Parameters of the law. beta/gamma/lambda index 0 = large (L), 1 = small (S).
struct ProfileLaw {
  double alpha = 0.1;
  double phiBulk = 0.6;
  double beta[2] = {0.1, 0.0};
  double gamma[2] = {0.9, 0.45};
  double lambda[2] = {1.0, 0.5};
  bool bidisperse = false;

  /// phi(y).
  double operator()(double y) const;
};

struct ProfileFitDef {
  bool bidisperse = false;  ///< fit the S term too
  int maxIterations = 500;
  double yMin = 0.0;  ///< fit only points with y > yMin [d_L]
  void validate() const;
};

struct ProfileFit {
  bool ok = false;
  std::string reason;      ///< why not ok (empty if ok)
  ProfileLaw law;          ///< best-fit parameters
  ProfileLaw error;        ///< standard errors, same layout
  double chiSquare = 0.0;  ///< sum of squared residuals
  int dof = 0;             ///< points - parameters
  int iterations = 0;
  double rms = 0.0;  ///< sqrt(chi^2 / dof)
};

/// Fits the law to (y, phi). Does not throw on a failed fit: ok = false with a reason (too few
/// points, no convergence, a non-physical alpha, gamma or lambda). Throws std::invalid_argument
/// when y and phi differ in size.
ProfileFit fitProfile(const std::vector<double>& y, const std::vector<double>& phi, const ProfileFitDef& def = {});

/// Initial guess from the data (documented above).
ProfileLaw initialGuess(const std::vector<double>& y, const std::vector<double>& phi, bool bidisperse);

}  // namespace confpack::analysis
