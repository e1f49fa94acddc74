#include "backends/nscd/ipm_solver.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#ifdef _OPENMP
#include <omp.h>
#endif

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

/// CHOLMOD's supernodal factorisation (SuiteSparse 5) opens OpenMP teams of a fixed 4 threads
/// for copy loops of a few hundred flops each: on 2 cores, 7.5 million futex calls in a 20 s
/// finisher, a third of its time spent in the kernel. While one lives, OpenMP may
/// give a team fewer threads than asked when the cores are busy (dynamic adjustment); those loops'
/// results do not depend on their team.
class DynamicOpenMpTeams {
 public:
#ifdef _OPENMP
  DynamicOpenMpTeams() : saved_(omp_get_dynamic()) { omp_set_dynamic(1); }
  ~DynamicOpenMpTeams() { omp_set_dynamic(saved_); }

 private:
  int saved_;
#endif
};

/// One normal unknown: the Jacobian pieces of its bodies (b < 0: the static world).
struct IpmRow {
  Vec3 n, axn, bxn;
  double bias = 0.0;   // c of the contact law
  int a = 0, b = -1;   // local body indices
};

/// Largest alpha > 0 (infinity if none) with v + alpha dv >= 0 componentwise.
double stepToBoundary(const Eigen::VectorXd& v, const Eigen::VectorXd& dv) {
  double alpha = std::numeric_limits<double>::infinity();
  for (Eigen::Index k = 0; k < v.size(); ++k)
    if (dv[k] < 0.0) alpha = std::min(alpha, -v[k] / dv[k]);
  return alpha;
}

}  // namespace

struct IpmSolver::Impl {
  // A factorisation that fails (not positive definite to round-off) is reported through info(),
  // which the solve handles; CHOLMOD would also print it on stderr, in the middle of a run's
  // progress.
  Impl() {
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
  std::vector<int> position;  // row k -> its index among the closed ones, or -1
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

IpmSolver::IpmSolver() : impl_(std::make_unique<Impl>()) {}
IpmSolver::~IpmSolver() = default;
IpmSolver::IpmSolver(IpmSolver&&) noexcept = default;
IpmSolver& IpmSolver::operator=(IpmSolver&&) noexcept = default;

int IpmSolver::solve(ContactRows& rows, const std::vector<BodyInverseMass>& bodies,
                     std::vector<BodyVelocity>& vel, const NscdSettings& settings) {
  Impl& s = *impl_;
  const DynamicOpenMpTeams dynamicTeams;
  const std::span<NormalRow> normalRows = rows.normalRows();
  const std::span<FrictionRow> frictionRows = rows.frictionRows();
  const std::size_t nN = normalRows.size(), m = nN + frictionRows.size();
  residual_ = 0.0;
  if (m == 0) {
    rows.storeNormalImpulses([](std::size_t) { return 0.0; });
    return 0;
  }
  const int world = static_cast<int>(bodies.size()) - 1;
  Eigen::VectorXd warm, scale;  // the rows' warm-start impulses; W_nn^-1/2, the unit MPRGP measures the residual in
  s.load(rows, bodies, warm, scale);
  const Eigen::Index N = s.size(), M = static_cast<Eigen::Index>(m);

  // v_base: the velocities without normal impulses (v_free plus the tangential impulses).
  std::vector<BodyVelocity> base(vel.begin(), vel.end());
  // b = J v_base + c, from the bodies' velocities.
  auto contactVelocities = [&](const std::vector<BodyVelocity>& v, Eigen::VectorXd& out) {
    out.resize(M);
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
  };
  // vel = base + M^-1 J^T r (the solvers' own update, with the rows' inverse masses).
  auto applyImpulses = [&](const Eigen::VectorXd& r) {
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
  };

  Eigen::VectorXd lam, rhs2, b, x, sl, r, rd, rp, rc, d, rhs, jt, dx, ds, dr, dxa, dsa, dra, mx, g, clean;
  int iterations = 0;
  double tangentChange = 0.0;
  const int outerCap = frictionRows.empty() ? 1 : settings.maxIterations;
  double innerTolerance = frictionRows.empty() ? settings.tolerance : std::max(settings.tolerance, 1e-4);
  bool analysed = false;
  for (int outer = 0; outer < outerCap; ++outer) {
    contactVelocities(base, b);
    const double bNorm = scale.cwiseProduct(b).norm();
    // Starting point: x = 0, s and r pushed into the interior by delta (in MPRGP's scaled units,
    // where impulses and velocities share a unit): contacts the warm start closed start with a
    // small s and their impulse, the others with their free velocity and a small impulse.
    const double delta = 1e-2 * std::max({scale.cwiseProduct(b).cwiseAbs().maxCoeff(),
                                          warm.cwiseQuotient(scale).maxCoeff(), 1e-300});
    x.setZero(N);
    sl.resize(M);
    r.resize(M);
    for (Eigen::Index k = 0; k < M; ++k) {
      sl[k] = std::max(b[k], delta / scale[k]);
      r[k] = std::max(warm[k], delta * scale[k]);
    }
    // The residual of the contact law at impulses `imp` >= 0 (those > 0 are the closed contacts);
    // leaves vel = base + M^-1 J^T imp and the contact velocities in g.
    auto lawResidual = [&](const Eigen::VectorXd& imp) {
      applyImpulses(imp);
      contactVelocities(vel, g);
      double sum = 0.0;
      for (Eigen::Index k = 0; k < M; ++k) {
        const double gp = imp[k] > 0.0 ? g[k] : std::min(g[k], 0.0);
        sum += scale[k] * scale[k] * gp * gp;
      }
      return bNorm > 0.0 ? std::sqrt(sum) / bNorm : 0.0;
    };
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
    auto polishRounds = [&](Eigen::VectorXd& imp, double best, bool fromImp, bool& wandered) {
      std::vector<char> active(static_cast<std::size_t>(M));
      for (Eigen::Index k = 0; k < M; ++k) active[static_cast<std::size_t>(k)] = imp[k] > 0.0;
      if (fromImp) lam = imp;  // else each round starts its sweeps from zero
      wandered = false;
      for (int round = 0; round < kPolishRounds && iterations < settings.maxIterations; ++round) {
        ++iterations;
        if (!fromImp) lam.setZero(M);
        if (!s.solveClosed(active, b, lam)) break;
        const auto closedBefore = std::count(active.begin(), active.end(), char{1});
        std::ptrdiff_t flips = 0;
        for (Eigen::Index k = 0; k < M; ++k)
          if (active[static_cast<std::size_t>(k)] && lam[k] <= 0.0) {
            lam[k] = 0.0;
            active[static_cast<std::size_t>(k)] = false;
            ++flips;
          }
        const double res = lawResidual(lam);
        if (res < best) {
          best = res;
          imp = lam;
        }
        if (best < innerTolerance) break;
        for (Eigen::Index k = 0; k < M; ++k)
          if (!active[static_cast<std::size_t>(k)] && g[k] < 0.0) {
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
    };
    auto polish = [&](Eigen::VectorXd& imp, double impResidual) {
      bool wandered = false;
      double best = polishRounds(imp, impResidual, false, wandered);
      if (wandered && best >= innerTolerance) best = polishRounds(imp, best, true, wandered);
      return best;
    };
    double polishedAt = std::numeric_limits<double>::infinity();
    // After a tangential pass the closed set hardly changes: the polish from the last impulses
    // first, the interior-point iterations only if it does not reach the tolerance.
    if (outer > 0) {
      clean = warm;
      residual_ = polish(clean, lawResidual(clean));
      polishedAt = residual_;
    }
    while (outer == 0 || residual_ >= innerTolerance) {
      clean.resize(M);  // closed: the impulse outweighs the contact velocity
      for (Eigen::Index k = 0; k < M; ++k) clean[k] = r[k] / (scale[k] * scale[k]) > sl[k] ? r[k] : 0.0;
      residual_ = lawResidual(clean);
      if (residual_ < innerTolerance || iterations >= settings.maxIterations) break;
      if (residual_ < kPolishFrom && residual_ < 1e-2 * polishedAt && analysed) {
        polishedAt = residual_;
        residual_ = polish(clean, residual_);
        if (residual_ < innerTolerance) break;
      }
      ++iterations;
      const double mu = sl.dot(r) / static_cast<double>(M);
      s.applyM(x, mx);
      s.applyJt(r, jt);
      rd = mx - jt;
      s.applyJ(x, rp);
      rp += b - sl;
      d = r.cwiseQuotient(sl);
      s.assemble(d);
      {
        const auto lock = blasLock();
        if (!analysed) {
          s.cholesky.analyzePattern(s.newton);
          analysed = true;
        }
        s.cholesky.factorize(s.newton);
      }
      if (s.cholesky.info() != Eigen::Success) {  // not positive definite to round-off: the polish's turn
        if (polishedAt > residual_) residual_ = polish(clean, residual_);
        break;
      }
      auto newtonStep = [&](const Eigen::VectorXd& target, Eigen::VectorXd& stepX, Eigen::VectorXd& stepS,
                            Eigen::VectorXd& stepR) {
        s.applyJt(target.cwiseQuotient(sl) - d.cwiseProduct(rp), jt);
        rhs = jt - rd;
        {
          const auto lock = blasLock();
          stepX = s.cholesky.solve(rhs);
        }
        s.applyJ(stepX, stepS);
        stepS += rp;
        stepR = (target - r.cwiseProduct(stepS)).cwiseQuotient(sl);
      };
      // Predictor (affine scaling), then the corrector with Mehrotra's centring sigma.
      rc = -sl.cwiseProduct(r);
      newtonStep(rc, dxa, dsa, dra);
      const double alphaAff = std::min({1.0, stepToBoundary(sl, dsa), stepToBoundary(r, dra)});
      const double muAff = (sl + alphaAff * dsa).dot(r + alphaAff * dra) / static_cast<double>(M);
      const double sigma = std::pow(muAff / mu, 3);
      rc -= dsa.cwiseProduct(dra);
      rc.array() += sigma * mu;
      newtonStep(rc, dx, ds, dr);
      const double step = std::min(1.0, kStepFraction * std::min(stepToBoundary(sl, ds), stepToBoundary(r, dr)));
      x += step * dx;
      sl += step * ds;
      r += step * dr;
    }
    residual_ = lawResidual(clean);  // vel = base + M^-1 J^T clean
    r = clean;
    if (frictionRows.empty()) break;
    // Block Gauss-Seidel with the tangential impulses of the wall points, as MPRGP's solve.
    const bool normalsConverged = innerTolerance <= settings.tolerance;
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
    tangentChange = sumR2 > 0.0 ? std::sqrt(sumDelta2 / sumR2) : 0.0;
    ++iterations;
    warm = r;
    if ((tangentChange < settings.tolerance && normalsConverged) || iterations >= settings.maxIterations) break;
    innerTolerance = std::max(settings.tolerance, std::min(innerTolerance, 0.1 * tangentChange));
  }
  residual_ = std::max(residual_, tangentChange);
  rows.storeNormalImpulses([&](std::size_t k) { return r[static_cast<Eigen::Index>(k)]; });
  for (std::size_t f = 0; f < frictionRows.size(); ++f) frictionRows[f].rn = r[static_cast<Eigen::Index>(nN + f)];
  return iterations;
}

}  // namespace confpack::nscd
