#pragma once
// Nonlinear fit of the wall-normal solid-fraction profile (docs/model.md,
// "Solid-fraction profiles and their fit"):
//
//   phi(y) = [1 - exp(-y/alpha)] x [ phi_bulk + sum_{i in {S,L}} beta_i cos(pi (2y - 1)/gamma_i) exp(-y/lambda_i) ]
//
// (y in d_L from the wall; monodisperse: beta_S = 0 and the S term is dropped, 5 parameters;
// bidisperse: 8). GSL's gsl_multifit_nlinear, trust region with Levenberg-Marquardt steps and
// the analytic Jacobian. The profile has no per-point errors, so the covariance (J^T J)^-1 is
// scaled by chi^2/dof (the residual variance) and by tau, the residuals' integrated
// autocorrelation in slices: slices d_L/50 thin are not independent (a grain spans many), and n
// residuals correlated over tau slices carry the information of n/tau independent ones. The
// standard errors then describe the scatter of the data around the law (tau = 1 for white noise).
//
// Bounds: alpha, gamma_i and lambda_i are fitted through a logistic map onto an interval,
// p = lo + (hi - lo) / (1 + e^-u), u free (ProfileBounds): they stay positive, the large grains'
// period and the small grains' stay apart (the two terms cannot swap roles), and a lambda the data
// do not fix runs to its upper bound, twice the profile's span, instead of to 1e9. The standard
// errors are those of the natural parameters, from the Jacobian in p at the minimum.
//
// Initial guesses from the data (the fit does not converge to the layering from a blind start):
// phi_bulk = mean of the profile over its last d_L (one layering period); gamma_L = distance
// between the first two maxima of the profile (default 0.9 d_L when there are not two);
// lambda_L = gamma / ln((p1 - phi_b)/(p2 - phi_b)) from the first two peak heights (default 1);
// beta_L = (p1 - phi_b) exp(y1/lambda_L); alpha = 0.1. Small grains start at half the large
// grains' gamma and lambda and a tenth of beta. A few starts around these (alpha x {1, 0.5, 2},
// lambda x {1, 0.5, 2}; bidisperse, each with gamma_S at half gamma_L and at 0.47 d_L) are run and
// the lowest chi^2 is kept, a start ending with alpha or a gamma at its bound excepted. ProfileFitDef::start, when
// given, is the one start (a leave-one-out mean fitted from the full mean's minimum, analysis/profile_average.hpp).
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

/// The intervals of the bounded parameters [d_L]; lambda's upper bound is twice the profile's span.
struct ProfileBounds {
  double alpha[2] = {0.005, 0.5};
  double gammaL[2] = {0.75, 1.6};  ///< large grains' period (about d_L)
  double gammaS[2] = {0.2, 0.6};   ///< small grains' period (about d_S = d_L / 2); apart from gamma_L's, or
                                   ///< the two terms can cancel each other with huge betas
  double lambdaMin = 0.02;
};

struct ProfileFitDef {
  bool bidisperse = false;  ///< fit the S term too
  int maxIterations = 500;
  double yMin = 0.0;  ///< fit only points with y > yMin [d_L]
  ProfileBounds bounds{};
  std::optional<ProfileLaw> start;  ///< the one start, instead of the starts around the data's guess
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
  double rms = 0.0;                ///< sqrt(chi^2 / dof)
  double correlationSlices = 1.0;  ///< tau, the residuals' integrated autocorrelation [slices]
  /// Whether the data fix lambda_L (index 0) and lambda_S (1): a lambda longer than the profile's
  /// span, or at its lower bound, is not determined. lambda_L not determined makes ok false;
  /// lambda_S not determined does not (lambda_L is still measured).
  bool lambdaDetermined[2] = {false, false};
};

/// Fits the law to (y, phi). Does not throw on a failed fit: ok = false with a reason (too few
/// points, no convergence, a singular covariance, a lambda_L the data do not fix). Throws std::invalid_argument
/// when y and phi differ in size.
ProfileFit fitProfile(const std::vector<double>& y, const std::vector<double>& phi, const ProfileFitDef& def = {});

/// Initial guess from the data (documented above).
ProfileLaw initialGuess(const std::vector<double>& y, const std::vector<double>& phi, bool bidisperse);

}  // namespace confpack::analysis
