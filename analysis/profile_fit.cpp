#include "analysis/profile_fit.hpp"

#include <fmt/format.h>
#include <gsl/gsl_blas.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <new>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "core/interrupt.hpp"

namespace confpack::analysis {

double ProfileLaw::operator()(double y) const {
  double b = phiBulk;
  for (int i = 0; i < (bidisperse ? 2 : 1); ++i)
    b += beta[i] * std::cos(std::numbers::pi * (2.0 * y - 1.0) / gamma[i]) * std::exp(-y / lambda[i]);
  return (1.0 - std::exp(-y / alpha)) * b;
}

void ProfileFitDef::validate() const {
  if (maxIterations < 1)
    throw std::invalid_argument(fmt::format("profile fit: max_iterations must be >= 1 (got {})", maxIterations));
}

namespace {

// Parameter vector layout: alpha, phi_b, beta_L, gamma_L, lambda_L [, beta_S, gamma_S, lambda_S].
int parameterCount(bool bi) {
  return bi ? 8 : 5;
}

ProfileLaw fromVector(const gsl_vector* x, bool bi) {
  ProfileLaw l;
  l.bidisperse = bi;
  l.alpha = gsl_vector_get(x, 0);
  l.phiBulk = gsl_vector_get(x, 1);
  for (int i = 0; i < (bi ? 2 : 1); ++i) {
    l.beta[i] = gsl_vector_get(x, 2 + 3 * i);
    l.gamma[i] = gsl_vector_get(x, 3 + 3 * i);
    l.lambda[i] = gsl_vector_get(x, 4 + 3 * i);
  }
  if (!bi) l.beta[1] = 0.0;
  return l;
}

void toVector(const ProfileLaw& l, gsl_vector* x) {
  gsl_vector_set(x, 0, l.alpha);
  gsl_vector_set(x, 1, l.phiBulk);
  for (int i = 0; i < (l.bidisperse ? 2 : 1); ++i) {
    gsl_vector_set(x, 2 + 3 * i, l.beta[i]);
    gsl_vector_set(x, 3 + 3 * i, l.gamma[i]);
    gsl_vector_set(x, 4 + 3 * i, l.lambda[i]);
  }
}

// A parameter's interval, or none (lo = hi = 0): p = lo + (hi - lo) s(u), s the logistic function.
struct Bound {
  double lo = 0.0, hi = 0.0;
  bool bounded() const { return hi > lo; }
  double toNatural(double u) const { return bounded() ? lo + (hi - lo) / (1.0 + std::exp(-u)) : u; }
  double toFree(double p) const {
    if (!bounded()) return p;
    // Strictly inside: a start on a bound would have a zero derivative.
    const double margin = 1e-3 * (hi - lo);
    const double q = std::clamp(p, lo + margin, hi - margin);
    return std::log((q - lo) / (hi - q));
  }
  double derivative(double p) const { return bounded() ? (p - lo) * (hi - p) / (hi - lo) : 1.0; }
  bool atBound(double p) const { return bounded() && std::min(p - lo, hi - p) < 1e-3 * (hi - lo); }
};

// Intervals in the order of the parameter vector; lambda up to twice the span of the data.
std::vector<Bound> boundsOf(const ProfileBounds& b, bool bi, double extent) {
  std::vector<Bound> out(parameterCount(bi));
  out[0] = {b.alpha[0], b.alpha[1]};
  out[3] = {b.gammaL[0], b.gammaL[1]};
  out[4] = {b.lambdaMin, std::max(2.0 * extent, 2.0 * b.lambdaMin)};
  if (bi) {
    out[6] = {b.gammaS[0], b.gammaS[1]};
    out[7] = out[4];
  }
  return out;
}

struct Data {
  const std::vector<double>* y;
  const std::vector<double>* phi;
  bool bi;
  std::vector<Bound> bounds;
  gsl_vector* natural;  // scratch: the natural parameters of the free ones
};

const gsl_vector* naturalOf(const gsl_vector* u, const Data& d) {
  for (std::size_t i = 0; i < d.bounds.size(); ++i)
    gsl_vector_set(d.natural, i, d.bounds[i].toNatural(gsl_vector_get(u, i)));
  return d.natural;
}

ProfileLaw lawOf(const gsl_vector* u, const Data& d) {
  return fromVector(naturalOf(u, d), d.bi);
}

int residuals(const gsl_vector* x, void* params, gsl_vector* f) {
  const Data& d = *static_cast<Data*>(params);
  const ProfileLaw l = lawOf(x, d);
  for (std::size_t k = 0; k < d.y->size(); ++k) gsl_vector_set(f, k, l((*d.y)[k]) - (*d.phi)[k]);
  return GSL_SUCCESS;
}

// Analytic Jacobian. With A = 1 - e^{-y/alpha}, B the bracket, c_i = cos(pi(2y-1)/gamma_i),
// s_i = sin(...), e_i = e^{-y/lambda_i}:
//   df/dalpha = -(y/alpha^2) e^{-y/alpha} B,   df/dphi_b = A,   df/dbeta_i = A c_i e_i,
//   df/dgamma_i = A beta_i e_i s_i pi (2y-1)/gamma_i^2,   df/dlambda_i = A beta_i c_i e_i y/lambda_i^2.
void naturalJacobian(const ProfileLaw& l, const Data& d, gsl_matrix* jac) {
  for (std::size_t k = 0; k < d.y->size(); ++k) {
    const double y = (*d.y)[k];
    const double ea = std::exp(-y / l.alpha), a = 1.0 - ea;
    double b = l.phiBulk;
    for (int i = 0; i < (d.bi ? 2 : 1); ++i) {
      const double arg = std::numbers::pi * (2.0 * y - 1.0) / l.gamma[i];
      const double c = std::cos(arg), s = std::sin(arg), e = std::exp(-y / l.lambda[i]);
      b += l.beta[i] * c * e;
      gsl_matrix_set(jac, k, 2 + 3 * i, a * c * e);
      gsl_matrix_set(jac, k, 3 + 3 * i,
                     a * l.beta[i] * e * s * std::numbers::pi * (2.0 * y - 1.0) / (l.gamma[i] * l.gamma[i]));
      gsl_matrix_set(jac, k, 4 + 3 * i, a * l.beta[i] * c * e * y / (l.lambda[i] * l.lambda[i]));
    }
    gsl_matrix_set(jac, k, 0, -(y / (l.alpha * l.alpha)) * ea * b);
    gsl_matrix_set(jac, k, 1, a);
  }
}

// In the free parameters: each bounded column times dp/du.
int jacobian(const gsl_vector* x, void* params, gsl_matrix* jac) {
  const Data& d = *static_cast<Data*>(params);
  const gsl_vector* p = naturalOf(x, d);
  naturalJacobian(fromVector(p, d.bi), d, jac);
  for (std::size_t i = 0; i < d.bounds.size(); ++i) {
    const double dp = d.bounds[i].derivative(gsl_vector_get(p, i));
    if (dp != 1.0)
      for (std::size_t k = 0; k < d.y->size(); ++k) gsl_matrix_set(jac, k, i, gsl_matrix_get(jac, k, i) * dp);
  }
  return GSL_SUCCESS;
}

// Local maxima of a lightly smoothed profile (3-point running mean), y ascending.
std::vector<std::size_t> peaks(const std::vector<double>& phi) {
  std::vector<double> s(phi.size());
  for (std::size_t k = 0; k < phi.size(); ++k) {
    const std::size_t lo = k > 0 ? k - 1 : k, hi = std::min(phi.size() - 1, k + 1);
    s[k] = (phi[lo] + phi[k] + phi[hi]) / 3.0;
  }
  std::vector<std::size_t> out;
  for (std::size_t k = 1; k + 1 < s.size(); ++k)
    if (s[k] > s[k - 1] && s[k] >= s[k + 1]) out.push_back(k);
  return out;
}

struct Attempt {
  ProfileFit fit;
  bool valid = false;
};

// GSL's objects, freed on every way out. GSL's allocators return NULL when memory runs out (its
// error handler is off, fitProfile), and its functions dereference what they are given: a NULL
// checked here becomes std::bad_alloc, the same failure as any other allocation's, instead of a
// segfault inside gsl_multifit_nlinear_winit.
struct GslFree {
  void operator()(gsl_multifit_nlinear_workspace* w) const { gsl_multifit_nlinear_free(w); }
  void operator()(gsl_vector* v) const { gsl_vector_free(v); }
  void operator()(gsl_matrix* m) const { gsl_matrix_free(m); }
};
template <class T>
using GslPtr = std::unique_ptr<T, GslFree>;

template <class T>
GslPtr<T> checked(T* allocated) {
  if (allocated == nullptr) throw std::bad_alloc();
  return GslPtr<T>(allocated);
}

// What gsl_multifit_nlinear_driver does (iterate, test for convergence with xtol = gtol = ftol =
// 1e-10, up to maxIterations; GSL_ENOPROG on the first iteration ends it), the same calls in the
// same order, with a safe point between iterations: GSL's own loop cannot be left early (a
// callback that fails only makes each remaining iteration fail, and it goes on to maxIterations,
// seconds on a long profile). Returns false, the fit unfinished, when SIGINT or SIGTERM asked to
// stop.
bool drive(gsl_multifit_nlinear_workspace* w, int maxIterations, int& status, int& info) {
  constexpr double tolerance = 1e-10;
  std::size_t iteration = 0;
  do {
    if (core::stopSignal() != 0) return false;
    status = gsl_multifit_nlinear_iterate(w);
    if (status == GSL_ENOPROG && iteration == 0) {
      info = status;
      status = GSL_EMAXITER;
      return true;
    }
    ++iteration;
    status = gsl_multifit_nlinear_test(tolerance, tolerance, tolerance, &info, w);
  } while (status == GSL_CONTINUE && iteration < static_cast<std::size_t>(maxIterations));
  // Converged to machine precision (a tolerance below it): success, the reason in info.
  if (status == GSL_ETOLF || status == GSL_ETOLX || status == GSL_ETOLG) {
    info = status;
    status = GSL_SUCCESS;
  }
  if (iteration >= static_cast<std::size_t>(maxIterations) && status != GSL_SUCCESS) status = GSL_EMAXITER;
  return true;
}

// The residuals' integrated autocorrelation, tau = 1 + 2 sum_{j>=1} rho_j, the sum over the lags
// before the first rho_j <= 0 (the initial positive sequence; Geyer 1992), at most n/4 of them.
double correlationSlices(const gsl_vector* r) {
  const std::size_t n = r->size;
  double mean = 0.0, var = 0.0;
  for (std::size_t k = 0; k < n; ++k) mean += gsl_vector_get(r, k) / static_cast<double>(n);
  for (std::size_t k = 0; k < n; ++k) var += std::pow(gsl_vector_get(r, k) - mean, 2);
  if (!(var > 0.0)) return 1.0;
  double tau = 1.0;
  for (std::size_t lag = 1; lag <= n / 4; ++lag) {
    double c = 0.0;
    for (std::size_t k = lag; k < n; ++k) c += (gsl_vector_get(r, k) - mean) * (gsl_vector_get(r, k - lag) - mean);
    const double rho = c / var;
    if (rho <= 0.0) break;
    tau += 2.0 * rho;
  }
  return tau;
}

// fitProfile's starts: alpha and lambda of the initial guess each times 1, 1/2 and 2, for each
// of two small grains' periods when bidisperse (or the given start alone).
constexpr int kStarts = 18;

Attempt runFit(const std::vector<double>& y, const std::vector<double>& phi, const ProfileLaw& start,
               const ProfileFitDef& def, int attempt) {
  Attempt at;
  const bool bi = def.bidisperse;
  const std::size_t n = y.size(), p = parameterCount(bi);
  const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
  const auto natural = checked(gsl_vector_alloc(p));
  Data data{&y, &phi, bi, boundsOf(def.bounds, bi, *hi - *lo), natural.get()};
  gsl_multifit_nlinear_fdf fdf;
  fdf.f = residuals;
  fdf.df = jacobian;
  fdf.fvv = nullptr;
  fdf.n = n;
  fdf.p = p;
  fdf.params = &data;
  gsl_multifit_nlinear_parameters params = gsl_multifit_nlinear_default_parameters();
  params.trs = gsl_multifit_nlinear_trs_lm;
  const auto workspace = checked(gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &params, n, p));
  gsl_multifit_nlinear_workspace* w = workspace.get();
  const auto x0 = checked(gsl_vector_alloc(p));
  const auto covar = checked(gsl_matrix_alloc(p, p));
  toVector(start, x0.get());
  for (std::size_t i = 0; i < p; ++i) gsl_vector_set(x0.get(), i, data.bounds[i].toFree(gsl_vector_get(x0.get(), i)));
  int info = 0;
  int status = gsl_multifit_nlinear_init(x0.get(), &fdf, w);
  // GSL_ENOMEM: an allocation inside GSL failed (the error handler is off).
  if (status == GSL_ENOMEM) throw std::bad_alloc();
  if (status == GSL_SUCCESS && !drive(w, def.maxIterations, status, info)) {
    // Stopped; no exception crosses GSL's C frames (drive returned first).
    const int iterations = static_cast<int>(gsl_multifit_nlinear_niter(w));
    throw core::Interrupted(core::stopSignal(),
                            fmt::format("while fitting the phi(y) profile ({} points, start {} of {}, iteration {})", n,
                                        attempt, kStarts, iterations + 1));
  }
  ProfileFit& f = at.fit;
  f.iterations = static_cast<int>(gsl_multifit_nlinear_niter(w));
  f.law = lawOf(gsl_multifit_nlinear_position(w), data);
  double chisq = 0.0;
  gsl_blas_ddot(gsl_multifit_nlinear_residual(w), gsl_multifit_nlinear_residual(w), &chisq);
  f.chiSquare = chisq;
  f.dof = static_cast<int>(n - p);
  f.rms = std::sqrt(chisq / f.dof);
  if (status != GSL_SUCCESS) {
    f.reason = fmt::format("no convergence ({})", gsl_strerror(status));
  } else {
    // The covariance of the natural parameters: the Jacobian in p at the minimum.
    const auto jac = checked(gsl_matrix_alloc(n, p));
    naturalJacobian(f.law, data, jac.get());
    if (gsl_multifit_nlinear_covar(jac.get(), 0.0, covar.get()) == GSL_ENOMEM) throw std::bad_alloc();
    f.correlationSlices = correlationSlices(gsl_multifit_nlinear_residual(w));
    const double scale = chisq / f.dof * f.correlationSlices;
    const auto err = checked(gsl_vector_alloc(p));
    bool finite = true;
    for (std::size_t i = 0; i < p; ++i) {
      const double v = gsl_matrix_get(covar.get(), i, i) * scale;
      finite = finite && std::isfinite(v) && v >= 0.0;
      gsl_vector_set(err.get(), i, std::sqrt(std::max(0.0, v)));
    }
    f.error = fromVector(err.get(), bi);
    const ProfileLaw& l = f.law;
    bool physical = l.alpha > 0.0 && l.gamma[0] > 0.0 && l.lambda[0] > 0.0 && std::isfinite(chisq);
    if (bi) physical = physical && l.gamma[1] > 0.0 && l.lambda[1] > 0.0;
    // A period at its bound is no layering found: the two terms beating against each other (at
    // the bounds between gamma_S and gamma_L, with large betas of opposite signs) or a
    // wavelength the data do not hold. Such a start is not kept, however low its chi^2.
    std::string atBound;
    if (data.bounds[0].atBound(f.law.alpha)) atBound = "alpha";
    if (data.bounds[3].atBound(f.law.gamma[0])) atBound = "gamma_L";
    if (bi && data.bounds[6].atBound(f.law.gamma[1])) atBound = "gamma_S";
    if (!physical)
      f.reason = "non-physical parameters (alpha, gamma or lambda <= 0)";
    else if (!atBound.empty())
      f.reason = fmt::format("{} at the bound of its interval (no layering of that period in the data)", atBound);
    else if (!finite)
      f.reason = "singular covariance (parameters not determined by the data)";
    else {
      f.ok = true;
      at.valid = true;
    }
  }
  return at;
}

}  // namespace

ProfileLaw initialGuess(const std::vector<double>& y, const std::vector<double>& phi, bool bidisperse) {
  ProfileLaw l;
  l.bidisperse = bidisperse;
  const double yEnd = y.back();
  double sum = 0.0;
  int count = 0;
  for (std::size_t k = 0; k < y.size(); ++k)
    if (y[k] >= yEnd - 1.0) {
      sum += phi[k];
      ++count;
    }
  l.phiBulk = count > 0 ? sum / count : phi.back();
  const std::vector<std::size_t> pk = peaks(phi);
  // First peak: the highest in the first d_L; second: the highest in (first + 0.5, first + 1.5).
  std::optional<std::size_t> p1, p2;
  for (std::size_t k : pk)
    if (y[k] < 1.0 && (!p1 || phi[k] > phi[*p1])) p1 = k;
  if (p1)
    for (std::size_t k : pk)
      if (y[k] > y[*p1] + 0.5 && y[k] < y[*p1] + 1.5 && (!p2 || phi[k] > phi[*p2])) p2 = k;
  l.gamma[0] = p1 && p2 ? y[*p2] - y[*p1] : 0.9;
  l.lambda[0] = 1.0;
  if (p1 && p2) {
    const double r = (phi[*p1] - l.phiBulk) / (phi[*p2] - l.phiBulk);
    if (r > 1.0 && std::isfinite(r)) l.lambda[0] = std::clamp(l.gamma[0] / std::log(r), 0.1, 10.0);
  }
  l.beta[0] = p1 ? (phi[*p1] - l.phiBulk) * std::exp(y[*p1] / l.lambda[0]) : 0.1;
  if (!(l.beta[0] > 0.0)) l.beta[0] = 0.1;
  l.alpha = 0.1;
  l.gamma[1] = 0.5 * l.gamma[0];
  l.lambda[1] = 0.5 * l.lambda[0];
  l.beta[1] = bidisperse ? 0.1 * l.beta[0] : 0.0;
  return l;
}

ProfileFit fitProfile(const std::vector<double>& yAll, const std::vector<double>& phiAll, const ProfileFitDef& def) {
  def.validate();
  if (yAll.size() != phiAll.size())
    throw std::invalid_argument(fmt::format("profile fit: {} positions for {} values", yAll.size(), phiAll.size()));
  // GSL's default handler aborts; errors are reported through status codes instead.
  static const gsl_error_handler_t* previous = gsl_set_error_handler_off();
  (void)previous;
  std::vector<double> y, phi;
  for (std::size_t k = 0; k < yAll.size(); ++k)
    if (yAll[k] > def.yMin && std::isfinite(phiAll[k])) {
      y.push_back(yAll[k]);
      phi.push_back(phiAll[k]);
    }
  ProfileFit best;
  const int p = parameterCount(def.bidisperse);
  if (static_cast<int>(y.size()) < 2 * p) {
    best.reason = fmt::format("too few profile points ({}) for {} parameters", y.size(), p);
    return best;
  }
  ProfileLaw guess = def.start ? *def.start : initialGuess(y, phi, def.bidisperse);
  guess.bidisperse = def.bidisperse;
  if (!def.bidisperse) guess.beta[1] = 0.0;
  // A given start is the minimum's basin already: that one start alone.
  const std::vector<double> factors = def.start ? std::vector<double>{1.0} : std::vector<double>{1.0, 0.5, 2.0};
  bool found = false;
  std::string lastReason;
  int attempt = 0;
  // Bidisperse: the small grains' period from the guess (half the large grains') and from about
  // their size, d_S = d_L / 2, a little less as layers of spheres nest.
  const std::vector<double> smallPeriods =
      def.bidisperse && !def.start ? std::vector<double>{guess.gamma[1], 0.47} : std::vector<double>{guess.gamma[1]};
  for (double gs : smallPeriods)
    for (double fa : factors)
      for (double fl : factors) {
        ProfileLaw start = guess;
        start.gamma[1] = gs;
        start.alpha *= fa;
        start.lambda[0] *= fl;
        start.lambda[1] *= fl;
        Attempt at = runFit(y, phi, start, def, ++attempt);
        if (!at.valid) {
          lastReason = at.fit.reason;
          continue;
        }
        if (!found || at.fit.chiSquare < best.chiSquare) {
          best = at.fit;
          found = true;
        }
      }
  if (!found) {
    best = ProfileFit{};
    best.reason = lastReason.empty() ? "no start converged" : lastReason;
    return best;
  }
  // A decay length beyond the profile's extent is not measured by it: the layering does not
  // decay within the data, and left free the fit would let lambda run away (to 1e9 d_L on 6 d_L
  // wide piles; bounded, to twice the span). Nor is one at its lower bound. Judged on the best
  // start only: another start's shorter lambda, with a larger chi^2, is no better measure of it.
  const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
  const double extent = *hi - *lo;
  const std::vector<Bound> bounds = boundsOf(def.bounds, def.bidisperse, extent);
  for (int i = 0; i < (def.bidisperse ? 2 : 1); ++i) {
    const double lambda = best.law.lambda[i];
    best.lambdaDetermined[i] = lambda <= extent && !bounds[4].atBound(lambda);
    if (i == 0 && !best.lambdaDetermined[0]) {
      best.ok = false;
      best.reason = lambda > extent ? fmt::format(
                                          "the layering does not decay within the profile: lambda_L = {:.3g} "
                                          "d_L is longer than the {:.3g} d_L it spans",
                                          lambda, extent)
                                    : fmt::format("lambda_L = {:.3g} d_L is at its lower bound", lambda);
    }
  }
  return best;
}

}  // namespace confpack::analysis
