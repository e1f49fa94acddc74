#include "backends/nscd/quasi_static_solver.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace confpack::nscd {

using core::Mat3;
using core::Vec3;

namespace {

/// Penalty of a row relative to its Delassus diagonal: large, so that an outer step recovers the
/// multipliers almost exactly, and small enough that H + A^T K A keeps some 8 digits in an LDL^T.
constexpr double kPenalty = 1e8;
constexpr double kFirstPenalty = 1e2;
constexpr int kMaxOuter = 60;
constexpr int kMaxNewton = 400;
/// Converged when no row is violated by more than this [d_L] and the multipliers moved by less
/// than kForceTolerance of the largest: far below what the equilibrium test resolves (1e-4).
constexpr double kGapTolerance = 1e-12;
constexpr double kForceTolerance = 1e-9;

}  // namespace

void QuasiStaticSolver::buildRows(const std::vector<ContactGeometry>& contacts, const std::vector<Vec3>& positions,
                                  const core::BoxDef& box, bool rotations, std::size_t bodyCount) {
  const int per = rotations ? 6 : 3;
  int rows = 0;
  for (const ContactGeometry& c : contacts) rows += c.pointCount;
  triplets_.clear();
  b_.resize(rows);
  int r = 0;
  auto put = [&](int row, int body, const Vec3& n, const Vec3& lxn, double sign) {
    for (int k = 0; k < 3; ++k) triplets_.emplace_back(row, per * body + k, sign * n[k]);
    if (rotations)
      for (int k = 0; k < 3; ++k) triplets_.emplace_back(row, per * body + 3 + k, sign * lxn[k]);
  };
  for (const ContactGeometry& c : contacts) {
    const Vec3 pb = c.b >= 0 ? Vec3(positions[c.b] + Vec3(c.shiftX * box.lengthX, c.shiftY * box.width, 0.0))
                             : Vec3::Zero();
    for (int p = 0; p < c.pointCount; ++p, ++r) {
      put(r, c.a, c.normal, (c.points[p] - positions[c.a]).cross(c.normal), -1.0);
      if (c.b >= 0) put(r, c.b, c.normal, (c.points[p] - pb).cross(c.normal), 1.0);
      b_[r] = -c.gaps[p];
    }
  }
  a_.resize(rows, per * static_cast<int>(bodyCount));
  a_.setFromTriplets(triplets_.begin(), triplets_.end());
}

QuasiStaticSolver::Outcome QuasiStaticSolver::solve(const std::vector<ContactGeometry>& contacts,
                                                    const std::vector<Vec3>& positions,
                                                    const std::vector<Body>& bodies, const core::BoxDef& box,
                                                    bool rotations, double h, const std::vector<double>& warmForces,
                                                    std::vector<Vec3>& displacement, std::vector<Vec3>& rotation,
                                                    std::vector<double>& forces) {
  const std::size_t n = bodies.size();
  const int per = rotations ? 6 : 3;
  const int dof = per * static_cast<int>(n);
  buildRows(contacts, positions, box, rotations, n);
  const int m = static_cast<int>(a_.rows());

  // H and F, and each row's Delassus diagonal W_ii = A_i H^-1 A_i^T for its penalty.
  triplets_.clear();
  f_.setZero(dof);
  std::vector<Mat3> invInertia(rotations ? n : 0);
  const double h2 = h * h;
  for (std::size_t i = 0; i < n; ++i) {
    const int base = per * static_cast<int>(i);
    for (int k = 0; k < 3; ++k) {
      triplets_.emplace_back(base + k, base + k, bodies[i].mass / h2);
      f_[base + k] = bodies[i].force[k];
    }
    if (rotations) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) triplets_.emplace_back(base + 3 + r, base + 3 + c, bodies[i].inertia(r, c) / h2);
      invInertia[i] = bodies[i].inertia.inverse();
    }
  }
  h_.resize(dof, dof);
  h_.setFromTriplets(triplets_.begin(), triplets_.end());
  k_.resize(m);
  {
    int r = 0;
    for (const ContactGeometry& c : contacts) {
      const Vec3 pb = c.b >= 0 ? Vec3(positions[c.b] + Vec3(c.shiftX * box.lengthX, c.shiftY * box.width, 0.0))
                               : Vec3::Zero();
      for (int p = 0; p < c.pointCount; ++p, ++r) {
        double w = h2 / bodies[c.a].mass;
        if (rotations) {
          const Vec3 lxn = (c.points[p] - positions[c.a]).cross(c.normal);
          w += h2 * lxn.dot(invInertia[c.a] * lxn);
        }
        if (c.b >= 0) {
          w += h2 / bodies[c.b].mass;
          if (rotations) {
            const Vec3 lxn = (c.points[p] - pb).cross(c.normal);
            w += h2 * lxn.dot(invInertia[c.b] * lxn);
          }
        }
        k_[r] = kPenalty / w;
      }
    }
  }

  lambda_.setZero(m);
  if (static_cast<int>(warmForces.size()) == m)
    for (int r = 0; r < m; ++r) lambda_[r] = std::max(0.0, warmForces[r]);
  x_.setZero(dof);

  // The pattern of H + A^T A once; each Newton iteration refactorises with the active rows' k_i
  // (inactive rows weigh 0 but keep their place in the pattern).
  Eigen::SparseMatrix<double> at = a_.transpose();
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(m);
  Eigen::SparseMatrix<double> kkt = h_ + at * weight.asDiagonal() * a_;
  ldlt_.analyzePattern(kkt);

  Outcome out;
  Eigen::VectorXd ax(m), adx(m), y(m), grad(dof), dx(dof), hdx(dof);
  std::vector<char> active(m, 0);
  // The penalty grows tenfold per outer iteration from kFirstPenalty to kPenalty: a soft start
  // keeps the first Newton steps from jumping between pieces of phi; the multipliers of the
  // warm start make the later, stiff problems small corrections.
  double penalty = kFirstPenalty;
  for (out.outerIterations = 1; out.outerIterations <= kMaxOuter; ++out.outerIterations) {
    const Eigen::VectorXd k = (penalty / kPenalty) * k_;
    // Inner: minimise phi for the current multipliers by semismooth Newton.
    bool lastFull = false;
    for (int inner = 0; inner < 50 && out.newtonIterations < kMaxNewton; ++inner) {
      ax = a_ * x_;
      y = lambda_ - k.cwiseProduct(ax - b_);
      grad = h_ * x_ - f_ - at * y.cwiseMax(0.0);
      // phi is quadratic on each piece: after a full Newton step that stayed on its piece (the
      // active rows unchanged) x is the exact minimiser.
      bool same = inner > 0;
      for (int r = 0; r < m; ++r) {
        const char on = y[r] > 0.0;
        same = same && on == active[r];
        active[r] = on;
      }
      if (same && lastFull) break;
      for (int r = 0; r < m; ++r) weight[r] = active[r] ? k[r] : 0.0;
      kkt = h_ + at * weight.asDiagonal() * a_;
      ldlt_.factorize(kkt);
      if (ldlt_.info() != Eigen::Success) throw std::runtime_error("nscd finisher: factorisation failed");
      dx = ldlt_.solve(-grad);
      ++out.newtonIterations;
      // Exact line search: phi is convex and piecewise quadratic along dx, its slope
      //   phi'(t) = grad.dx + t dx.H dx - sum_i [max(0, y_i - t k_i (A dx)_i) - max(0, y_i)] (A dx)_i
      // piecewise linear and increasing; a full step when phi'(1) <= 0, else bisection.
      adx = a_ * dx;
      hdx = h_ * dx;
      const double g0 = grad.dot(dx), curvature = dx.dot(hdx);
      auto slope = [&](double t) {
        double v = g0 + t * curvature;
        for (int r = 0; r < m; ++r) {
          const double yr = y[r], zr = k[r] * adx[r];
          v -= (std::max(0.0, yr - t * zr) - std::max(0.0, yr)) * adx[r];
        }
        return v;
      };
      double t = 1.0;
      if (slope(1.0) > 0.0) {
        double lo = 0.0, hi = 1.0;
        for (int it = 0; it < 60 && hi - lo > 1e-14; ++it) {
          const double mid = 0.5 * (lo + hi);
          (slope(mid) > 0.0 ? hi : lo) = mid;
        }
        t = hi;
      }
      x_ += t * dx;
      lastFull = t == 1.0;
      if (t * dx.lpNorm<Eigen::Infinity>() <= 1e-15 * std::max(1.0, x_.lpNorm<Eigen::Infinity>())) break;
    }
    ax = a_ * x_;
    const Eigen::VectorXd next = (lambda_ - k.cwiseProduct(ax - b_)).cwiseMax(0.0);
    const double change = (next - lambda_).lpNorm<Eigen::Infinity>();
    lambda_ = next;
    out.infeasibility = m > 0 ? std::max(0.0, (b_ - ax).maxCoeff()) : 0.0;
    if (penalty >= kPenalty && out.infeasibility <= kGapTolerance &&
        change <= kForceTolerance * std::max(1e-300, lambda_.lpNorm<Eigen::Infinity>())) {
      out.converged = true;
      break;
    }
    if (out.newtonIterations >= kMaxNewton) break;
    penalty = std::min(kPenalty, 10.0 * penalty);
  }
  out.outerIterations = std::min(out.outerIterations, kMaxOuter);

  displacement.resize(n);
  rotation.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const int base = per * static_cast<int>(i);
    displacement[i] = x_.segment<3>(base);
    rotation[i] = rotations ? Vec3(x_.segment<3>(base + 3)) : Vec3::Zero();
  }
  forces.assign(lambda_.data(), lambda_.data() + m);
  return out;
}

}  // namespace confpack::nscd
