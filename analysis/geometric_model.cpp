#include "analysis/geometric_model.hpp"

#include <fmt/format.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_fit.h>
#include <gsl/gsl_statistics_double.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace confpack::analysis {

namespace {
void checkSizes(std::size_t n, std::size_t m, const std::vector<double>& sigma, std::size_t minimum) {
  if (n != m) throw std::invalid_argument(fmt::format("fit: {} abscissae for {} values", n, m));
  if (n < minimum) throw std::invalid_argument(fmt::format("fit: needs at least {} points (got {})", minimum, n));
  if (!sigma.empty() && sigma.size() != n)
    throw std::invalid_argument(fmt::format("fit: {} sigmas for {} values", sigma.size(), n));
  for (double s : sigma)
    if (!(s > 0.0) || !std::isfinite(s))
      throw std::invalid_argument(fmt::format("fit: sigma must be positive (got {})", s));
}
}  // namespace

ConfinementFit fitConfinement(const std::vector<double>& width, const std::vector<double>& value,
                              const std::vector<double>& sigma) {
  checkSizes(width.size(), value.size(), sigma, 2);
  const std::size_t n = width.size();
  std::vector<double> x(n), w;
  for (std::size_t k = 0; k < n; ++k) {
    if (!(width[k] > 0.0) || !std::isfinite(width[k]))
      throw std::invalid_argument(fmt::format("fit: width must be positive (got {})", width[k]));
    x[k] = 1.0 / width[k];
  }
  ConfinementFit f;
  f.dof = static_cast<int>(n) - 2;
  double c0 = 0, c1 = 0, cov00 = 0, cov01 = 0, cov11 = 0, chisq = 0;
  if (!sigma.empty()) {
    for (double s : sigma) w.push_back(1.0 / (s * s));
    gsl_fit_wlinear(x.data(), 1, w.data(), 1, value.data(), 1, n, &c0, &c1, &cov00, &cov01, &cov11, &chisq);
    f.weighted = true;
    if (f.dof > 0) f.quality = gsl_cdf_chisq_Q(chisq, f.dof);
  } else {
    // gsl_fit_linear scales the covariance by chi^2/(n-2): NaN for 2 points, reported as 0 there.
    gsl_fit_linear(x.data(), 1, value.data(), 1, n, &c0, &c1, &cov00, &cov01, &cov11, &chisq);
    if (f.dof == 0) cov00 = cov01 = cov11 = 0.0;
  }
  f.bulk = c0;
  f.c = -c1;
  f.bulkError = std::sqrt(std::max(0.0, cov00));
  f.cError = std::sqrt(std::max(0.0, cov11));
  f.covariance = -cov01;
  f.chiSquare = chisq;
  return f;
}

LineFit fitLine(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& sigma) {
  checkSizes(x.size(), y.size(), sigma, 2);
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  if (!(*hi > *lo)) throw std::invalid_argument(fmt::format("line fit: every point at x = {} (no slope)", *lo));
  const std::size_t n = x.size();
  LineFit f;
  f.dof = static_cast<int>(n) - 2;
  double cov00 = 0, cov01 = 0, cov11 = 0;
  if (!sigma.empty()) {
    std::vector<double> w;
    for (double s : sigma) w.push_back(1.0 / (s * s));
    gsl_fit_wlinear(x.data(), 1, w.data(), 1, y.data(), 1, n, &f.intercept, &f.slope, &cov00, &cov01, &cov11,
                    &f.chiSquare);
    f.weighted = true;
    if (f.dof > 0) f.quality = gsl_cdf_chisq_Q(f.chiSquare, f.dof);
  } else {
    gsl_fit_linear(x.data(), 1, y.data(), 1, n, &f.intercept, &f.slope, &cov00, &cov01, &cov11, &f.chiSquare);
    if (f.dof == 0) cov00 = cov01 = cov11 = 0.0;
  }
  f.interceptError = std::sqrt(std::max(0.0, cov00));
  f.slopeError = std::sqrt(std::max(0.0, cov11));
  f.covariance = cov01;
  const auto [ylo, yhi] = std::minmax_element(y.begin(), y.end());
  if (*yhi > *ylo) f.correlation = gsl_stats_correlation(x.data(), 1, y.data(), 1, n);
  return f;
}

ProportionalFit fitThroughOrigin(const std::vector<double>& x, const std::vector<double>& y,
                                 const std::vector<double>& sigma) {
  checkSizes(x.size(), y.size(), sigma, 1);
  ProportionalFit f;
  f.dof = static_cast<int>(x.size()) - 1;
  double c1 = 0, cov11 = 0, sumsq = 0;
  if (!sigma.empty()) {
    std::vector<double> w;
    for (double s : sigma) w.push_back(1.0 / (s * s));
    gsl_fit_wmul(x.data(), 1, w.data(), 1, y.data(), 1, x.size(), &c1, &cov11, &sumsq);
  } else {
    gsl_fit_mul(x.data(), 1, y.data(), 1, x.size(), &c1, &cov11, &sumsq);
    if (f.dof == 0) cov11 = 0.0;
  }
  f.slope = c1;
  f.slopeError = std::sqrt(std::max(0.0, cov11));
  f.chiSquare = sumsq;
  return f;
}

double profileIntegralC(const SolidFractionProfile& profile, double phiBulk) {
  double s = 0.0;
  for (double v : profile.phi) s += (phiBulk - v) * profile.slice;
  return 2.0 * s;
}

}  // namespace confpack::analysis
