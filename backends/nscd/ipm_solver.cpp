#include "backends/nscd/ipm_solver.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "backends/nscd/thread_choice.hpp"
#include "core/blas_lock.hpp"

namespace confpack::nscd {

using core::Mat3;
using core::Vec3;

// Mehrotra's predictor-corrector (Nocedal & Wright, "Numerical Optimization", 2nd ed., 16.6) for
//     min 1/2 x.M x  subject to  s = J x + b >= 0,
// unknowns x (velocity changes of the bodies with rows), s (contact velocities u_n + c) and r
// (normal impulses). Residuals
//     r_d = M x - J^T r,   r_p = J x + b - s,   complementarity s o r -> 0.
// The Newton step for a complementarity target r_c (predictor: -s o r; corrector:
// -s o r - ds_aff o dr_aff + sigma mu) is
//     (M + J^T D J) dx = -r_d + J^T (r_c / s - D r_p),   D = r / s,
//     ds = J dx + r_p,   dr = (r_c - r o ds) / s,
// and the step along it the largest in [0, 1] that keeps s, r >= 0, times 0.995.
// Stopping rule: the contact law itself, measured as MPRGP measures it. Contacts whose impulse
// outweighs their velocity (r W_nn > s) are taken as closed, the others' impulses set to zero;
// the velocities are then v_free + M^-1 J^T r exactly, and the scaled projected gradient of the
// dual at r (u_n + c on closed contacts, min(u_n + c, 0) on open ones) relative to its value at
// r = 0 must be below the tolerance. So the impulses and velocities it returns satisfy the
// momentum balance to round-off, whatever the accuracy of the last Newton step.

namespace {

constexpr double kStepFraction = 0.995;  // of the step to the boundary of s, r >= 0
// The polish starts below this residual of the contact law and tries at most kPolishRounds
// active sets in each of its two starts (from zero, then from the interior point's impulses).
constexpr double kPolishFrom = 1e-3;
constexpr int kPolishRounds = 6;
// The polish solves W_AA r_A = -b_A by proximal-point sweeps (solveFactorised), from zero or from
// the interior point's impulses (the polish, below). A pinacoid's face contact carries up to 8
// points for 3 constraints, so W_AA is singular there: sweeps from the interior point keep its
// positive split of a face's load between the points, where the least impulses split it with
// negative ones, which the active-set correction opens, round after round, without converging
// (a 235-pinacoid pile's finisher: 49 of 51 solves near 1e-14 against 3 of 42 below 1e-10,
// docs/performance.md, "The interior point's polish"). eps, the shift that makes the singular
// W_AA factorisable, is 1e-10 of its largest diagonal entry: a sweep leaves a residual of eps
// times its change.
constexpr double kProximalWeight = 1e-10;
constexpr int kProximalSweeps = 20;
// A polish round that opens or closes more than 1 % of the closed contacts (at least this many)
// started far from the solution's active set: the polish stops there (and starts again from the
// interior point's impulses if it started from zero).
constexpr std::ptrdiff_t kPolishFlips = 10;

// CHOLMOD's factorisations and solves call BLAS: each holds core::blasLock() (core/blas_lock.hpp).
using core::blasLock;

/// One normal unknown: the Jacobian pieces of its bodies (b < 0: the static world).
struct IpmRow {
  Vec3 n, axn, bxn;
  double bias = 0.0;  // c of the contact law
  int a = 0, b = -1;  // local body indices
};

/// Largest alpha > 0 (infinity if none) with v + alpha dv >= 0 componentwise.
double stepToBoundary(const Eigen::VectorXd& v, const Eigen::VectorXd& dv) {
  double alpha = std::numeric_limits<double>::infinity();
  for (Eigen::Index k = 0; k < v.size(); ++k)
    if (dv[k] < 0.0) alpha = std::min(alpha, -v[k] / dv[k]);
  return alpha;
}

/// The problem of a solve's rows (Jacobians, body map, masses), the Newton matrix M + J^T D J and
/// its factorisation, and the polish's Delassus matrix and its factorisation.
struct IpmProblem {
  // A factorisation that fails (not positive definite to round-off) is reported through info(),
  // which the solve handles; CHOLMOD would also print it on stderr, in the middle of a run's
  // progress.
  IpmProblem() {
    cholesky.cholmod().print = 0;
    delassusCholesky.cholmod().print = 0;
  }

  std::vector<IpmRow> rows;
  std::vector<int> local;   // body -> local body index, -1 without rows
  std::vector<int> global;  // local body index -> body
  int dof = 3;              // per body: 3 (spheres: no row turns a body) or 6
  Eigen::SparseMatrix<double> newton;
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> cholesky;
  std::vector<Mat3> inertia;  // world-frame inertia of each local body (dof 6)
  std::vector<Mat3> invInertia;
  std::vector<double> mass;
  // The polish's Delassus matrix W_AA of the closed contacts and its factorisation.
  Eigen::SparseMatrix<double> delassus;
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> delassusCholesky;
  std::vector<int> position;     // row k -> its index among the closed ones, or -1
  std::vector<char> factorised;  // the closed set delassusCholesky holds (empty: none)
  double proximal = 0.0;         // eps of solveFactorised, kProximalWeight of W_AA's largest diagonal entry

  // u_k restricted to local body `body` (6 entries; the angular ones unused when dof is 3).
  static Eigen::Matrix<double, 6, 1> rowOn(const IpmRow& row, bool onB) {
    Eigen::Matrix<double, 6, 1> u;
    u.head<3>() = onB ? row.n : Vec3(-row.n);
    u.tail<3>() = onB ? row.bxn : Vec3(-row.axn);
    return u;
  }
  // W_kl = sum over the bodies they share of u_k.M_i^-1 u_l.
  double coupling(const Eigen::Matrix<double, 6, 1>& uk, const Eigen::Matrix<double, 6, 1>& ul, int body) const {
    double w = uk.head<3>().dot(ul.head<3>()) / mass[static_cast<std::size_t>(body)];
    if (dof == 6) w += uk.tail<3>().dot(invInertia[static_cast<std::size_t>(body)] * ul.tail<3>());
    return w;
  }

  // r_A = -W_AA^-1 b_A for the rows with active[k], the others 0, into `r`; false if the
  // factorisation failed.
  bool solveClosed(const std::vector<char>& active, const Eigen::VectorXd& b, Eigen::VectorXd& r) {
    if (active == factorised && delassusCholesky.info() == Eigen::Success) return solveFactorised(b, r);
    factorised.clear();
    position.assign(rows.size(), -1);
    int nA = 0;
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (active[k]) position[k] = nA++;
    if (nA == 0) {
      r.setZero();
      return true;
    }
    // Rows by body, then every pair of closed rows on a body: one entry of W_AA each.
    std::vector<std::vector<std::pair<int, Eigen::Matrix<double, 6, 1>>>> onBody(global.size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      if (!active[k]) continue;
      onBody[static_cast<std::size_t>(rows[k].a)].emplace_back(position[k], rowOn(rows[k], false));
      if (rows[k].b >= 0) onBody[static_cast<std::size_t>(rows[k].b)].emplace_back(position[k], rowOn(rows[k], true));
    }
    triplets.clear();
    for (std::size_t i = 0; i < onBody.size(); ++i)
      for (const auto& [k, uk] : onBody[i])
        for (const auto& [l, ul] : onBody[i])
          if (k >= l) triplets.emplace_back(k, l, coupling(uk, ul, static_cast<int>(i)));
    delassus.resize(nA, nA);
    delassus.setFromTriplets(triplets.begin(), triplets.end());
    proximal = kProximalWeight * delassus.diagonal().maxCoeff();
    for (int k = 0; k < nA; ++k) delassus.coeffRef(k, k) += proximal;
    {
      const auto lock = blasLock();
      delassusCholesky.compute(delassus);
    }
    if (delassusCholesky.info() != Eigen::Success) return false;
    factorised = active;
    return solveFactorised(b, r);
  }
  // The proximal-point iteration r <- (W_AA + eps I)^-1 (-b_A + eps r) from the impulses `r` holds
  // on entry: each sweep leaves W_AA r + b_A = -eps (r - r_previous), so it stops when a sweep
  // changes r by less than 1e-14 of |b_A| / eps.
  bool solveFactorised(const Eigen::VectorXd& b, Eigen::VectorXd& r) {
    const Eigen::Index nA = delassus.rows();
    Eigen::VectorXd minusB(nA), closed(nA), next;
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (position[k] >= 0) {
        minusB[position[k]] = -b[static_cast<Eigen::Index>(k)];
        closed[position[k]] = r[static_cast<Eigen::Index>(k)];
      }
    const double enough = 1e-14 * minusB.norm();
    for (int sweep = 0; sweep < kProximalSweeps; ++sweep) {
      {
        const auto lock = blasLock();
        next = delassusCholesky.solve(minusB + proximal * closed);
      }
      const double change = proximal * (next - closed).norm();
      closed.swap(next);
      if (change <= enough) break;
    }
    for (std::size_t k = 0; k < rows.size(); ++k)
      r[static_cast<Eigen::Index>(k)] = position[k] >= 0 ? closed[position[k]] : 0.0;
    return true;
  }

  int size() const { return dof * static_cast<int>(global.size()); }

  // The problem of `rows`: one IpmRow per normal unknown (the frictionless rows, then the normal
  // part of the side-wall friction rows), the bodies that carry a row in order of first appearance
  // with their masses, and per row its warm-start impulse and W_nn^-1/2.
  void load(const ContactRows& rows, const std::vector<BodyInverseMass>& bodies, Eigen::VectorXd& warm,
            Eigen::VectorXd& scale) {
    const std::span<const NormalRow> normalRows = rows.normalRows();
    const std::span<const FrictionRow> frictionRows = rows.frictionRows();
    const std::size_t nN = normalRows.size(), m = nN + frictionRows.size();
    const int world = static_cast<int>(bodies.size()) - 1;
    factorised.clear();  // new rows: nothing factorised yet
    local.assign(bodies.size(), -1);
    global.clear();
    auto localOf = [&](int body) {
      if (body == world) return -1;
      if (local[body] < 0) {
        local[body] = static_cast<int>(global.size());
        global.push_back(body);
      }
      return local[body];
    };
    this->rows.resize(m);
    warm.resize(static_cast<Eigen::Index>(m));
    scale.resize(static_cast<Eigen::Index>(m));
    for (std::size_t k = 0; k < nN; ++k) {
      const NormalRow& row = normalRows[k];
      this->rows[k] = {row.n, row.axn, row.bxn, row.bias, localOf(row.a), localOf(row.b)};
      scale[static_cast<Eigen::Index>(k)] = std::sqrt(row.invW);
      warm[static_cast<Eigen::Index>(k)] = row.r;
    }
    for (std::size_t f = 0; f < frictionRows.size(); ++f) {
      const FrictionRow& row = frictionRows[f];
      this->rows[nN + f] = {row.n, row.axn, Vec3::Zero(), row.bias, localOf(row.a), -1};
      scale[static_cast<Eigen::Index>(nN + f)] = std::sqrt(row.invWnn);
      warm[static_cast<Eigen::Index>(nN + f)] = row.rn;
    }
    dof = rows.turnsNoBody() ? 3 : 6;
    const std::size_t nb = global.size();
    mass.resize(nb);
    inertia.resize(nb);
    invInertia.resize(nb);
    for (std::size_t i = 0; i < nb; ++i) {
      const BodyInverseMass& body = bodies[static_cast<std::size_t>(global[i])];
      mass[i] = 1.0 / body.invMass;
      if (dof == 6) {
        inertia[i] = body.invInertia.inverse();
        invInertia[i] = body.invInertia;
      }
    }
  }

  // Jacobian row k applied to x: u_k = n.(v_b - v_a) + (l_b x n).w_b - (l_a x n).w_a.
  double applyRow(const IpmRow& row, const Eigen::VectorXd& x) const {
    const int a = dof * row.a;
    double u = -row.n.dot(x.segment<3>(a));
    if (dof == 6) u -= row.axn.dot(x.segment<3>(a + 3));
    if (row.b >= 0) {
      const int b = dof * row.b;
      u += row.n.dot(x.segment<3>(b));
      if (dof == 6) u += row.bxn.dot(x.segment<3>(b + 3));
    }
    return u;
  }
  void applyJ(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
    out.resize(static_cast<Eigen::Index>(rows.size()));
    for (std::size_t k = 0; k < rows.size(); ++k) out[static_cast<Eigen::Index>(k)] = applyRow(rows[k], x);
  }
  // out = J^T y.
  void applyJt(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
    out.setZero(size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const IpmRow& row = rows[k];
      const double yk = y[static_cast<Eigen::Index>(k)];
      const int a = dof * row.a;
      out.segment<3>(a) -= yk * row.n;
      if (dof == 6) out.segment<3>(a + 3) -= yk * row.axn;
      if (row.b >= 0) {
        const int b = dof * row.b;
        out.segment<3>(b) += yk * row.n;
        if (dof == 6) out.segment<3>(b + 3) += yk * row.bxn;
      }
    }
  }
  void applyM(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
    out.resize(x.size());
    for (std::size_t i = 0; i < global.size(); ++i) {
      const int o = dof * static_cast<int>(i);
      out.segment<3>(o) = mass[i] * x.segment<3>(o);
      if (dof == 6) out.segment<3>(o + 3) = inertia[i] * x.segment<3>(o + 3);
    }
  }

  // K = M + J^T D J, lower triangle, as triplets (duplicates summed by setFromTriplets).
  void assemble(const Eigen::VectorXd& d) {
    triplets.clear();
    auto add = [&](int i, int j, double v) {
      if (i >= j) triplets.emplace_back(i, j, v);
    };
    for (std::size_t i = 0; i < global.size(); ++i) {
      const int o = dof * static_cast<int>(i);
      for (int c = 0; c < 3; ++c) add(o + c, o + c, mass[i]);
      if (dof == 6)
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c <= r; ++c) add(o + 3 + r, o + 3 + c, inertia[i](r, c));
    }
    Eigen::Matrix<double, 6, 1> ua, ub;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const IpmRow& row = rows[k];
      const double dk = d[static_cast<Eigen::Index>(k)];
      ua.head<3>() = -row.n;
      ua.tail<3>() = -row.axn;
      ub.head<3>() = row.n;
      ub.tail<3>() = row.bxn;
      const int a = dof * row.a;
      for (int r = 0; r < dof; ++r)
        for (int c = 0; c <= r; ++c) add(a + r, a + c, dk * ua[r] * ua[c]);
      if (row.b < 0) continue;
      const int b = dof * row.b;
      for (int r = 0; r < dof; ++r)
        for (int c = 0; c <= r; ++c) add(b + r, b + c, dk * ub[r] * ub[c]);
      for (int r = 0; r < dof; ++r)  // the off-diagonal block, in the lower triangle
        for (int c = 0; c < dof; ++c) {
          add(a + r, b + c, dk * ua[r] * ub[c]);
          add(b + r, a + c, dk * ub[r] * ua[c]);
        }
    }
    newton.resize(size(), size());
    newton.setFromTriplets(triplets.begin(), triplets.end());
  }
};

/// The velocities as the rows see them: b = J v + c from the bodies' velocities, and
/// v = v_base + M^-1 J^T r with the rows' inverse masses (the solvers' own update), v_base the
/// velocities without normal impulses (v_free plus the tangential impulses).
struct RowVelocities {
  std::span<NormalRow> normalRows;
  std::span<FrictionRow> frictionRows;
  int world = 0;                   // the static world's body index
  std::vector<BodyVelocity>& vel;  // the solve's velocities
  std::vector<BodyVelocity> base;  // v_base

  void contactVelocities(const std::vector<BodyVelocity>& v, Eigen::VectorXd& out) const {
    const std::size_t nN = normalRows.size();
    out.resize(static_cast<Eigen::Index>(nN + frictionRows.size()));
    for (std::size_t k = 0; k < nN; ++k) {
      const NormalRow& row = normalRows[k];
      const BodyVelocity& va = v[static_cast<std::size_t>(row.a)];
      const BodyVelocity& vb = v[static_cast<std::size_t>(row.b)];
      out[static_cast<Eigen::Index>(k)] = normalVelocity(row, va, vb) + row.bias;
    }
    for (std::size_t f = 0; f < frictionRows.size(); ++f) {
      const FrictionRow& row = frictionRows[f];
      const BodyVelocity& va = v[static_cast<std::size_t>(row.a)];
      out[static_cast<Eigen::Index>(nN + f)] = normalVelocity(row, va) + row.bias;
    }
  }
  // vel = base + M^-1 J^T r.
  void applyImpulses(const Eigen::VectorXd& r) {
    const std::size_t nN = normalRows.size();
    vel.assign(base.begin(), base.end());
    for (std::size_t k = 0; k < nN; ++k) {
      const NormalRow& row = normalRows[k];
      const double rk = r[static_cast<Eigen::Index>(k)];
      vel[static_cast<std::size_t>(row.a)].v -= (rk * row.invMa) * row.n;
      vel[static_cast<std::size_t>(row.a)].w -= rk * row.iaAxn;
      if (row.b != world) {
        vel[static_cast<std::size_t>(row.b)].v += (rk * row.invMb) * row.n;
        vel[static_cast<std::size_t>(row.b)].w += rk * row.ibBxn;
      }
    }
    for (std::size_t f = 0; f < frictionRows.size(); ++f) {
      const FrictionRow& row = frictionRows[f];
      const double rk = r[static_cast<Eigen::Index>(nN + f)];
      vel[static_cast<std::size_t>(row.a)].v -= (rk * row.invMa) * row.n;
      vel[static_cast<std::size_t>(row.a)].w -= rk * row.iaAxn;
    }
  }
  // One projected pass over the tangential impulses of the wall points with the normal impulses
  // `r`, moving vel and v_base alike; returns the relative change of the impulses.
  double tangentPass(const Eigen::VectorXd& r) {
    const std::size_t nN = normalRows.size();
    double sumDelta2 = 0.0, sumR2 = 0.0;
    for (std::size_t f = 0; f < frictionRows.size(); ++f) {
      FrictionRow& row = frictionRows[f];
      row.rn = r[static_cast<Eigen::Index>(nN + f)];
      BodyVelocity& va = vel[static_cast<std::size_t>(row.a)];
      const BodyVelocity before = va;
      const auto [d1, d2] = updateTangent(row, va);
      base[static_cast<std::size_t>(row.a)].v += va.v - before.v;
      base[static_cast<std::size_t>(row.a)].w += va.w - before.w;
      sumDelta2 += d1 * d1 + d2 * d2;
      sumR2 += row.rn * row.rn + row.rt1 * row.rt1 + row.rt2 * row.rt2;
    }
    return sumR2 > 0.0 ? std::sqrt(sumDelta2 / sumR2) : 0.0;
  }
};

/// The interior point: velocity changes x, contact velocities s (sl) and impulses r.
struct InteriorPoint {
  Eigen::VectorXd x, sl, r;
};

/// The Newton system's right-hand sides and steps: residuals r_d, r_p, the complementarity
/// target r_c, D = r / s, the predictor's steps (dxa, dsa, dra) and the corrector's, and their scratch.
struct NewtonScratch {
  Eigen::VectorXd rd, rp, rc, d, rhs, jt, mx;
  Eigen::VectorXd dx, ds, dr, dxa, dsa, dra;
};

/// One solve of IpmSolver: block Gauss-Seidel between the normal problem (interior point, then
/// polish) and the tangential pass; its phases share the iterate and the scratch.
class IpmSolve {
 public:
  IpmSolve(IpmProblem& problem, ContactRows& rows, const std::vector<BodyInverseMass>& bodies,
           std::vector<BodyVelocity>& vel, const NscdSettings& settings)
      : problem_(problem),
        settings_(settings),
        rows_{rows.normalRows(), rows.frictionRows(), static_cast<int>(bodies.size()) - 1, vel,
              std::vector<BodyVelocity>(vel.begin(), vel.end())},
        m_(static_cast<Eigen::Index>(rows.normalRows().size() + rows.frictionRows().size())) {
    problem_.load(rows, bodies, warm_, scale_);
  }

  int run(ContactRows& rows);
  double residual() const { return residual_; }

 private:
  void startingPoint();
  void interiorPoint(int outer, double& polishedAt);
  bool factoriseNewton();
  void newtonStep(const Eigen::VectorXd& target, Eigen::VectorXd& stepX, Eigen::VectorXd& stepS,
                  Eigen::VectorXd& stepR);
  void predictorCorrector(double mu);
  double lawResidual(const Eigen::VectorXd& imp);
  double polishRounds(Eigen::VectorXd& imp, double best, bool fromImp, bool& wandered);
  double polish(Eigen::VectorXd& imp, double impResidual);

  IpmProblem& problem_;
  const NscdSettings& settings_;
  RowVelocities rows_;
  Eigen::Index m_ = 0;            // normal unknowns
  Eigen::VectorXd warm_, scale_;  // the rows' warm-start impulses; W_nn^-1/2, the unit MPRGP measures the residual in
  Eigen::VectorXd b_;             // b = J v_base + c
  double bNorm_ = 0.0;            // ||S b||, the scale of the residual
  InteriorPoint point_;
  NewtonScratch newton_;
  Eigen::VectorXd g_;      // the contact velocities of lawResidual's impulses
  Eigen::VectorXd clean_;  // the iterate's impulses on the contacts taken as closed, 0 on the others
  Eigen::VectorXd lam_;    // the polish's impulses
  int iterations_ = 0;
  double innerTolerance_ = 0.0;
  bool analysed_ = false;  // the Newton matrix's pattern is analysed
  double residual_ = 0.0;
};

int IpmSolve::run(ContactRows& rows) {
  double tangentChange = 0.0;
  const bool friction = !rows_.frictionRows.empty();
  const int outerCap = friction ? settings_.maxIterations : 1;
  innerTolerance_ = friction ? std::max(settings_.tolerance, 1e-4) : settings_.tolerance;
  for (int outer = 0; outer < outerCap; ++outer) {
    rows_.contactVelocities(rows_.base, b_);
    bNorm_ = scale_.cwiseProduct(b_).norm();
    startingPoint();
    double polishedAt = std::numeric_limits<double>::infinity();
    // After a tangential pass the closed set hardly changes: the polish from the last impulses
    // first, the interior-point iterations only if it does not reach the tolerance.
    if (outer > 0) {
      clean_ = warm_;
      residual_ = polish(clean_, lawResidual(clean_));
      polishedAt = residual_;
    }
    interiorPoint(outer, polishedAt);
    residual_ = lawResidual(clean_);  // vel = base + M^-1 J^T clean
    point_.r = clean_;
    if (!friction) break;
    // Block Gauss-Seidel with the tangential impulses of the wall points, as MPRGP's solve.
    const bool normalsConverged = innerTolerance_ <= settings_.tolerance;
    tangentChange = rows_.tangentPass(point_.r);
    ++iterations_;
    warm_ = point_.r;
    if ((tangentChange < settings_.tolerance && normalsConverged) || iterations_ >= settings_.maxIterations) break;
    innerTolerance_ = std::max(settings_.tolerance, std::min(innerTolerance_, 0.1 * tangentChange));
  }
  residual_ = std::max(residual_, tangentChange);
  const Eigen::VectorXd& r = point_.r;
  const std::size_t nN = rows_.normalRows.size();
  rows.storeNormalImpulses([&](std::size_t k) { return r[static_cast<Eigen::Index>(k)]; });
  for (std::size_t f = 0; f < rows_.frictionRows.size(); ++f)
    rows_.frictionRows[f].rn = r[static_cast<Eigen::Index>(nN + f)];
  return iterations_;
}

// Starting point: x = 0, s and r pushed into the interior by delta (in MPRGP's scaled units,
// where impulses and velocities share a unit): contacts the warm start closed start with a
// small s and their impulse, the others with their free velocity and a small impulse.
void IpmSolve::startingPoint() {
  const double delta =
      1e-2 * std::max({scale_.cwiseProduct(b_).cwiseAbs().maxCoeff(), warm_.cwiseQuotient(scale_).maxCoeff(), 1e-300});
  point_.x.setZero(problem_.size());
  point_.sl.resize(m_);
  point_.r.resize(m_);
  for (Eigen::Index k = 0; k < m_; ++k) {
    point_.sl[k] = std::max(b_[k], delta / scale_[k]);
    point_.r[k] = std::max(warm_[k], delta * scale_[k]);
  }
}

// Mehrotra's iterations from the starting point until the impulses they imply (clean_) meet the
// contact law to the inner tolerance, with the polish tried whenever the residual has fallen a
// hundredfold below kPolishFrom since it was last tried.
void IpmSolve::interiorPoint(int outer, double& polishedAt) {
  InteriorPoint& p = point_;
  while (outer == 0 || residual_ >= innerTolerance_) {
    clean_.resize(m_);  // closed: the impulse outweighs the contact velocity
    for (Eigen::Index k = 0; k < m_; ++k) clean_[k] = p.r[k] / (scale_[k] * scale_[k]) > p.sl[k] ? p.r[k] : 0.0;
    residual_ = lawResidual(clean_);
    if (residual_ < innerTolerance_ || iterations_ >= settings_.maxIterations) break;
    if (residual_ < kPolishFrom && residual_ < 1e-2 * polishedAt && analysed_) {
      polishedAt = residual_;
      residual_ = polish(clean_, residual_);
      if (residual_ < innerTolerance_) break;
    }
    ++iterations_;
    const double mu = p.sl.dot(p.r) / static_cast<double>(m_);
    if (!factoriseNewton()) {  // not positive definite to round-off: the polish's turn
      if (polishedAt > residual_) residual_ = polish(clean_, residual_);
      break;
    }
    predictorCorrector(mu);
  }
}

// The residuals r_d, r_p and D at the iterate, and the factorisation of M + J^T D J; false if it
// failed.
bool IpmSolve::factoriseNewton() {
  const InteriorPoint& p = point_;
  NewtonScratch& n = newton_;
  problem_.applyM(p.x, n.mx);
  problem_.applyJt(p.r, n.jt);
  n.rd = n.mx - n.jt;
  problem_.applyJ(p.x, n.rp);
  n.rp += b_ - p.sl;
  n.d = p.r.cwiseQuotient(p.sl);
  problem_.assemble(n.d);
  {
    const auto lock = blasLock();
    if (!analysed_) {
      problem_.cholesky.analyzePattern(problem_.newton);
      analysed_ = true;
    }
    problem_.cholesky.factorize(problem_.newton);
  }
  return problem_.cholesky.info() == Eigen::Success;
}

// The Newton step for the complementarity target `target`, through the factorisation.
void IpmSolve::newtonStep(const Eigen::VectorXd& target, Eigen::VectorXd& stepX, Eigen::VectorXd& stepS,
                          Eigen::VectorXd& stepR) {
  NewtonScratch& n = newton_;
  problem_.applyJt(target.cwiseQuotient(point_.sl) - n.d.cwiseProduct(n.rp), n.jt);
  n.rhs = n.jt - n.rd;
  {
    const auto lock = blasLock();
    stepX = problem_.cholesky.solve(n.rhs);
  }
  problem_.applyJ(stepX, stepS);
  stepS += n.rp;
  stepR = (target - point_.r.cwiseProduct(stepS)).cwiseQuotient(point_.sl);
}

// Predictor (affine scaling), then the corrector with Mehrotra's centring sigma, and the step
// along it: the largest in [0, 1] that keeps s, r >= 0, times kStepFraction.
void IpmSolve::predictorCorrector(double mu) {
  InteriorPoint& p = point_;
  NewtonScratch& n = newton_;
  n.rc = -p.sl.cwiseProduct(p.r);
  newtonStep(n.rc, n.dxa, n.dsa, n.dra);
  const double alphaAff = std::min({1.0, stepToBoundary(p.sl, n.dsa), stepToBoundary(p.r, n.dra)});
  const double muAff = (p.sl + alphaAff * n.dsa).dot(p.r + alphaAff * n.dra) / static_cast<double>(m_);
  const double sigma = std::pow(muAff / mu, 3);
  n.rc -= n.dsa.cwiseProduct(n.dra);
  n.rc.array() += sigma * mu;
  newtonStep(n.rc, n.dx, n.ds, n.dr);
  const double step = std::min(1.0, kStepFraction * std::min(stepToBoundary(p.sl, n.ds), stepToBoundary(p.r, n.dr)));
  p.x += step * n.dx;
  p.sl += step * n.ds;
  p.r += step * n.dr;
}

// The residual of the contact law at impulses `imp` >= 0 (those > 0 are the closed contacts);
// leaves vel = base + M^-1 J^T imp and the contact velocities in g_.
double IpmSolve::lawResidual(const Eigen::VectorXd& imp) {
  rows_.applyImpulses(imp);
  rows_.contactVelocities(rows_.vel, g_);
  double sum = 0.0;
  for (Eigen::Index k = 0; k < m_; ++k) {
    const double gp = imp[k] > 0.0 ? g_[k] : std::min(g_[k], 0.0);
    sum += scale_[k] * scale_[k] * gp * gp;
  }
  return bNorm_ > 0.0 ? std::sqrt(sum) / bNorm_ : 0.0;
}

// The polish: from the contacts closed in `imp`, the impulses that close exactly those,
// W_AA r_A = -b_A, by a sparse Cholesky factorisation of the Delassus matrix of the closed
// contacts and proximal-point sweeps (solveFactorised); then the active set corrected
// (negative impulses opened, penetrating open contacts closed) and again, until nothing
// changes. The sweeps start from zero, which gives the least impulses that close the set:
// no self-stress in a hyperstatic loop (two spheres between two walls carry nothing
// sideways). Where that wanders (a round changes more than 1 % of the set: pinacoid face
// contacts, whose points share a face's load in ways the least impulses make negative), the
// polish starts again with sweeps from `imp`, the interior point's positive split. Keeps in
// `imp` and returns the best residual it met.
double IpmSolve::polishRounds(Eigen::VectorXd& imp, double best, bool fromImp, bool& wandered) {
  std::vector<char> active(static_cast<std::size_t>(m_));
  for (Eigen::Index k = 0; k < m_; ++k) active[static_cast<std::size_t>(k)] = imp[k] > 0.0;
  if (fromImp) lam_ = imp;  // else each round starts its sweeps from zero
  wandered = false;
  for (int round = 0; round < kPolishRounds && iterations_ < settings_.maxIterations; ++round) {
    ++iterations_;
    if (!fromImp) lam_.setZero(m_);
    if (!problem_.solveClosed(active, b_, lam_)) break;
    const auto closedBefore = std::count(active.begin(), active.end(), char{1});
    std::ptrdiff_t flips = 0;
    for (Eigen::Index k = 0; k < m_; ++k)
      if (active[static_cast<std::size_t>(k)] && lam_[k] <= 0.0) {
        lam_[k] = 0.0;
        active[static_cast<std::size_t>(k)] = false;
        ++flips;
      }
    const double res = lawResidual(lam_);
    if (res < best) {
      best = res;
      imp = lam_;
    }
    if (best < innerTolerance_) break;
    for (Eigen::Index k = 0; k < m_; ++k)
      if (!active[static_cast<std::size_t>(k)] && g_[k] < 0.0) {
        active[static_cast<std::size_t>(k)] = true;
        ++flips;
      }
    if (flips == 0) break;
    if (flips > std::max<std::ptrdiff_t>(kPolishFlips, closedBefore / 100)) {
      wandered = true;
      break;
    }
  }
  return best;
}

double IpmSolve::polish(Eigen::VectorXd& imp, double impResidual) {
  bool wandered = false;
  double best = polishRounds(imp, impResidual, false, wandered);
  if (wandered && best >= innerTolerance_) best = polishRounds(imp, best, true, wandered);
  return best;
}

}  // namespace

struct IpmSolver::Impl {
  IpmProblem problem;
};

IpmSolver::IpmSolver() : impl_(std::make_unique<Impl>()) {}
IpmSolver::~IpmSolver() = default;
IpmSolver::IpmSolver(IpmSolver&&) noexcept = default;
IpmSolver& IpmSolver::operator=(IpmSolver&&) noexcept = default;

int IpmSolver::solve(ContactRows& rows, const std::vector<BodyInverseMass>& bodies, std::vector<BodyVelocity>& vel,
                     const NscdSettings& settings) {
  const DynamicOpenMpTeams dynamicTeams;
  residual_ = 0.0;
  if (rows.rowCount() == 0) {
    rows.storeNormalImpulses([](std::size_t) { return 0.0; });
    return 0;
  }
  IpmSolve solve(impl_->problem, rows, bodies, vel, settings);
  const int iterations = solve.run(rows);
  residual_ = solve.residual();
  return iterations;
}

}  // namespace confpack::nscd
