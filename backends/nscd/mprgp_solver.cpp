// MPRGP solver of the nscd contact problem (see contact_rows.hpp for the problem, contact_solver.hpp
// for the choice).
//
// Unknowns: the normal impulses of every contact point, k < nN the frictionless rows
// (normalRows()[k]), k >= nN the normal part of the side-wall friction rows (frictionRows()[k - nN],
// whose body b is the static world). In the scaled variables y = r / s with s = W_kk^-1/2 (Jacobi
// scaling keeps the bounds y >= 0 and gives A = S W S a unit diagonal) the step's problem is
//     minimise f(y) = 1/2 y.A y - y.b   subject to y >= 0,
//     gradient g = A y - b = S (u + c),  u = H^T v the relative normal velocities, c the gap term,
// whose optimality conditions are exactly the velocity Signorini law of contact_rows.hpp.
// A p is applied without forming W: impulses to body velocities (M^-1 H S p), then back to the rows
// (S H^T), two passes over the contact data.
//
// Parallel and deterministic: the per-body sums of M^-1 H S p run over each body's own rows (a
// fixed list built once per step), the per-row products are independent, and every dot product is
// summed in fixed blocks of rows, then over blocks in order. The arithmetic therefore does not
// depend on the number of threads: one thread and two give bitwise identical runs.
#include "backends/nscd/mprgp_solver.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <span>

namespace confpack::nscd {

using core::Vec3;

namespace {

/// Rows per block of a reduction; fixed, so sums do not depend on the thread count.
constexpr std::ptrdiff_t kBlock = 1024;
/// Below this many unknowns a parallel region costs more than it saves (measured, see header).
constexpr std::size_t kParallelMin = 4096;

/// sum_k term(k) over [0, m), summed per block of kBlock and then over blocks in order. `term` may
/// also write entry k of other arrays (each k is visited once).
template <class Term>
double blockedSum(std::size_t m, int threads, std::vector<double>& partial, const Term& term) {
  const std::ptrdiff_t blocks = (static_cast<std::ptrdiff_t>(m) + kBlock - 1) / kBlock;
  partial.assign(static_cast<std::size_t>(blocks), 0.0);
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && m >= kParallelMin)
  for (std::ptrdiff_t blk = 0; blk < blocks; ++blk) {
    const std::size_t end = std::min(m, static_cast<std::size_t>((blk + 1) * kBlock));
    double s = 0.0;
    for (std::size_t k = static_cast<std::size_t>(blk * kBlock); k < end; ++k) s += term(k);
    partial[static_cast<std::size_t>(blk)] = s;
  }
  double total = 0.0;
  for (double s : partial) total += s;
  return total;
}

/// body(0) and body(1) on a team of two threads (one thread takes both if the team is smaller).
/// Its own function, so that the parallel region does not share a frame with serial loops.
template <class Body>
[[gnu::noinline]] void onTwoThreads(const Body body) {
#pragma omp parallel num_threads(2)
  for (int blk = omp_get_thread_num(); blk < 2; blk += omp_get_num_threads()) body(blk);
}

}  // namespace

void MprgpSolver::buildMprgpRows(const ContactRows& rows, std::size_t bodyCount) {
  const std::span<const NormalRow> normalRows = rows.normalRows();
  const std::span<const FrictionRow> frictionRows = rows.frictionRows();
  // Gather rows: the scaled Jacobian of every unknown. Friction rows' normal parts act on the
  // static world (last body) as b, with zero lever arm there.
  const int world = static_cast<int>(bodyCount) - 1;
  const std::size_t nN = normalRows.size(), m = nN + frictionRows.size();
  gatherRows_.resize(m);
  for (std::size_t k = 0; k < nN; ++k) {
    const NormalRow& row = normalRows[k];
    const double s = scratch_.scale[k];
    gatherRows_[k] = {s * row.n, s * row.axn, s * row.bxn, s * row.bias, row.a, row.b};
  }
  for (std::size_t f = 0; f < frictionRows.size(); ++f) {
    const FrictionRow& row = frictionRows[f];
    const double s = scratch_.scale[nN + f];
    gatherRows_[nN + f] = {s * row.n, s * row.axn, Vec3::Zero(), s * row.bias, row.a, world};
  }
  // Spheres: the lever arm is along the normal, so l x n vanishes (to round-off) and a row moves
  // no angular velocity. When that holds for every row, the passes use copies without the angular
  // parts: half the bytes per iteration, which is what a pass over a large pile is bound by.
  linearOnly_ = rows.turnsNoBody();
  if (linearOnly_) {
    linearRows_.resize(m);
    for (std::size_t k = 0; k < m; ++k)
      linearRows_[k] = {gatherRows_[k].n, gatherRows_[k].bias, gatherRows_[k].a, gatherRows_[k].b};
  }
  // Scatter entries, grouped by body (counting sort, row order within a body); the world gets
  // none: its velocity never changes. Entry: unknown k and the velocity change per unit y_k.
  bodyEntryStart_.assign(bodyCount + 1, 0);
  for (const GatherRow& row : gatherRows_) {
    ++bodyEntryStart_[row.a + 1];
    if (row.b != world) ++bodyEntryStart_[row.b + 1];
  }
  for (std::size_t b = 0; b < bodyCount; ++b) bodyEntryStart_[b + 1] += bodyEntryStart_[b];
  bodyEntries_.resize(bodyEntryStart_[bodyCount]);
  bodyCursor_.assign(bodyEntryStart_.begin(), bodyEntryStart_.end() - 1);
  for (std::size_t k = 0; k < nN; ++k) {
    const NormalRow& row = normalRows[k];
    const double s = scratch_.scale[k];
    bodyEntries_[bodyCursor_[row.a]++] = {-(s * row.invMa) * row.n, -s * row.iaAxn, static_cast<int>(k)};
    if (row.b != world)
      bodyEntries_[bodyCursor_[row.b]++] = {(s * row.invMb) * row.n, s * row.ibBxn, static_cast<int>(k)};
  }
  for (std::size_t f = 0; f < frictionRows.size(); ++f) {
    const FrictionRow& row = frictionRows[f];
    const double s = scratch_.scale[nN + f];
    bodyEntries_[bodyCursor_[row.a]++] = {-(s * row.invMa) * row.n, -s * row.iaAxn, static_cast<int>(nN + f)};
  }
  sweepMass_.resize(m);
  for (std::size_t k = 0; k < nN; ++k) sweepMass_[k] = {normalRows[k].invMa, normalRows[k].invMb};
  for (std::size_t f = 0; f < frictionRows.size(); ++f) sweepMass_[nN + f] = {frictionRows[f].invMa, 0.0};
  if (!linearOnly_) {
    sweepAngular_.resize(m);
    for (std::size_t k = 0; k < nN; ++k)
      sweepAngular_[k] = {scratch_.scale[k] * normalRows[k].iaAxn, scratch_.scale[k] * normalRows[k].ibBxn};
    for (std::size_t f = 0; f < frictionRows.size(); ++f)
      sweepAngular_[nN + f] = {scratch_.scale[nN + f] * frictionRows[f].iaAxn, Vec3::Zero()};
  }
  if (linearOnly_) {
    linearEntries_.resize(bodyEntries_.size());
    for (std::size_t e = 0; e < bodyEntries_.size(); ++e)
      linearEntries_[e] = {bodyEntries_[e].linear, bodyEntries_[e].k};
  }
}

void MprgpSolver::applyImpulses(const std::vector<double>& y, std::vector<BodyVelocity>& out, int threads) const {
  const std::ptrdiff_t bodies = static_cast<std::ptrdiff_t>(out.size()) - 1;
  out.back() = BodyVelocity{};
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && y.size() >= kParallelMin)
  for (std::ptrdiff_t i = 0; i < bodies; ++i) {
    BodyVelocity dv;
    for (int e = bodyEntryStart_[i]; e < bodyEntryStart_[i + 1]; ++e) {
      const BodyEntry& entry = bodyEntries_[e];
      dv.v += y[entry.k] * entry.linear;
      dv.w += y[entry.k] * entry.angular;
    }
    out[i] = dv;
  }
}

void MprgpSolver::applyLinearImpulses(const std::vector<double>& y, std::vector<Vec3>& out, int threads) const {
  const std::ptrdiff_t bodies = static_cast<std::ptrdiff_t>(out.size()) - 1;
  out.back().setZero();
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && y.size() >= kParallelMin)
  for (std::ptrdiff_t i = 0; i < bodies; ++i) {
    Vec3 dv = Vec3::Zero();
    for (int e = bodyEntryStart_[i]; e < bodyEntryStart_[i + 1]; ++e)
      dv += y[linearEntries_[e].k] * linearEntries_[e].linear;
    out[i] = dv;
  }
}

void MprgpSolver::addImpulses(const std::vector<double>& y, std::vector<BodyVelocity>& vel, int threads) {
  if (linearOnly_) {
    scratch_.dvLinear.resize(vel.size());
    applyLinearImpulses(y, scratch_.dvLinear, threads);
    for (std::size_t b = 0; b < vel.size(); ++b) vel[b].v += scratch_.dvLinear[b];
    return;
  }
  scratch_.dv.resize(vel.size());
  applyImpulses(y, scratch_.dv, threads);
  for (std::size_t b = 0; b < vel.size(); ++b) {
    vel[b].v += scratch_.dv[b].v;
    vel[b].w += scratch_.dv[b].w;
  }
}

double MprgpSolver::contactVelocities(const std::vector<BodyVelocity>& vel, std::vector<double>& out, int threads) {
  if (linearOnly_)
    return blockedSum(out.size(), threads, scratch_.partial, [&](std::size_t k) {
      const LinearRow& row = linearRows_[k];
      out[k] = row.n.dot(vel[row.b].v - vel[row.a].v) + row.bias;
      return 0.0;
    });
  return blockedSum(out.size(), threads, scratch_.partial, [&](std::size_t k) {
    const GatherRow& row = gatherRows_[k];
    const BodyVelocity& va = vel[row.a];
    const BodyVelocity& vb = vel[row.b];
    out[k] = normalVelocity(row, va, vb) + row.bias;
    return 0.0;
  });
}

// Row k's scaled relative normal velocity S H^T dv for the body velocity changes dv in
// scratch_.dvLinear (spheres) or scratch_.dv.
inline double MprgpSolver::dvAlongRow(std::size_t k) const {
  if (linearOnly_) {
    const LinearRow& row = linearRows_[k];
    return row.n.dot(scratch_.dvLinear[row.b] - scratch_.dvLinear[row.a]);
  }
  const GatherRow& row = gatherRows_[k];
  const BodyVelocity& va = scratch_.dv[row.a];
  const BodyVelocity& vb = scratch_.dv[row.b];
  return normalVelocity(row, va, vb);
}

// out = A x = S H^T M^-1 H S x, in two passes (impulses to body velocities, then back to rows);
// returns out . x. Spheres (linearOnly_) move linear velocities only: 24 bytes per body instead of
// 48 between the passes, and no angular terms.
double MprgpSolver::applyOperator(const std::vector<double>& x, std::vector<double>& out, std::size_t bodyCount,
                                  int threads) {
  if (linearOnly_) {
    scratch_.dvLinear.resize(bodyCount);
    applyLinearImpulses(x, scratch_.dvLinear, threads);
  } else {
    scratch_.dv.resize(bodyCount);
    applyImpulses(x, scratch_.dv, threads);
  }
  return blockedSum(out.size(), threads, scratch_.partial, [&](std::size_t k) {
    out[k] = dvAlongRow(k);
    return out[k] * x[k];
  });
}

// Upper bound of ||A|| = ||S W S|| by Gershgorin: the largest absolute row sum, with the entries
// of A computed from the rows' own data (no W formed). A_kj = sum over the bodies b shared by rows
// k and j of (s_j J_jb) . (M_b^-1 J_kb s_k), i.e. row j's scaled Jacobian on b (a gather row)
// dotted with row k's velocity change per unit y_k on b (a scatter entry); |A_kj| is bounded by
// the sum over b of the absolute terms. Each body's entries pair up: sum_b |rows on b|^2 products,
// about 50 per grain for spheres (a few percent of a solve).
// Why not the Cauchy-Schwarz bound |A_kj| <= s_k s_j sqrt(w_kb w_jb): it ignores the angle between
// the normals and was up to 3.1 times ||A|| on a 493-sphere pile, this one 1.5 to 1.8 times, and
// Dostal's expansion step alpha_bar = 1.95 / bound is that much longer. With the default
// projected CG expansion alpha_bar serves only when that step is refused (rarely: under 0.05
// times a step there).
double MprgpSolver::scaledOperatorBound(std::size_t bodyCount) {
  const std::size_t m = gatherRows_.size();
  scratch_.rowSum.assign(m, 0.0);
  for (std::size_t body = 0; body + 1 < bodyCount; ++body) {  // the world (last) has no entries
    const int first = bodyEntryStart_[body], last = bodyEntryStart_[body + 1];
    for (int f = first; f < last; ++f) {
      const int j = bodyEntries_[f].k;
      const GatherRow& row = gatherRows_[j];
      // Row j's scaled Jacobian on this body: u_j = n.(v_b - v_a) + (l_b x n).w_b - (l_a x n).w_a.
      const bool onA = row.a == static_cast<int>(body);
      const Vec3 linear = onA ? Vec3(-row.n) : row.n;
      const Vec3 angular = onA ? Vec3(-row.axn) : row.bxn;
      double sum = 0.0;
      for (int e = first; e < last; ++e)
        sum += std::abs(linear.dot(bodyEntries_[e].linear) + angular.dot(bodyEntries_[e].angular));
      scratch_.rowSum[static_cast<std::size_t>(j)] += sum;
    }
  }
  return m > 0 ? *std::max_element(scratch_.rowSum.begin(), scratch_.rowSum.end()) : 0.0;
}

double MprgpSolver::frictionTangentPass(ContactRows& rows, std::vector<BodyVelocity>& vel, double omega) {
  double sumDelta2 = 0.0, sumR2 = 0.0;
  const std::size_t nN = rows.normalRows().size();
  const std::span<FrictionRow> frictionRows = rows.frictionRows();
  for (std::size_t f = 0; f < frictionRows.size(); ++f) {
    FrictionRow& row = frictionRows[f];
    row.rn = scratch_.scale[nN + f] * scratch_.y[nN + f];
    const auto [d1, d2] = updateTangent(row, vel[row.a], omega);
    sumDelta2 += d1 * d1 + d2 * d2;
    sumR2 += row.rn * row.rn + row.rt1 * row.rt1 + row.rt2 * row.rt2;
  }
  return sumR2 > 0.0 ? std::sqrt(sumDelta2 / sumR2) : 0.0;
}

// The expansion step of Kruzik et al. (2020), "Active set expansion strategies in MPRGP
// algorithm": y <- P(y - alpha_cg p), the conjugate gradient step that was too
// long for y >= 0, projected on it. Kept only if it lowers f, which changes by exactly
// g.d + 1/2 d.A d for the step d; then y, g move by d, A d and the function returns true. Otherwise
// nothing moves and Dostal's expansion follows (A p is still in scratch_.ap). One application of A, as
// Dostal's expansion, whose fresh gradient costs one too.
// Unlike Dostal's expansion, conjugate gradients do not restart after it: the next direction is
// phi - gamma p with gamma = phi.A p / p.A p (`phiAp` returns phi.A p), restricted to the new free
// set, and a restart from phi happens only if that is not a descent direction. f still decreases at
// every step. On a loading pile it takes about a quarter fewer iterations than Dostal's expansion,
// and fewer than restarting after the projected step would (docs/performance.md, "nscd settings:
// the measurements behind the defaults").
bool MprgpSolver::projectedCgStep(double alphaCg, std::size_t bodyCount, int threads, double& phiAp) {
  const std::size_t m = scratch_.y.size();
  const double gDotD = blockedSum(m, threads, scratch_.partial, [&](std::size_t k) {
    scratch_.step[k] = std::max(0.0, scratch_.y[k] - alphaCg * scratch_.p[k]) - scratch_.y[k];
    return scratch_.g[k] * scratch_.step[k];
  });
  const double dAd = applyOperator(scratch_.step, scratch_.aStep, bodyCount, threads);
  if (!(gDotD + 0.5 * dAd < 0.0)) return false;
  phiAp = blockedSum(m, threads, scratch_.partial, [&](std::size_t k) {
    scratch_.y[k] = std::max(0.0, scratch_.y[k] - alphaCg * scratch_.p[k]);  // not y + d: exactly zero at the bound
    scratch_.g[k] += scratch_.aStep[k];
    return scratch_.y[k] > 0.0 ? scratch_.g[k] * scratch_.ap[k] : 0.0;
  });
  return true;
}

// The projected CG step at alphaCg; with the exact preconditioner, when that raises f, at half
// the length, and so on kHalvings times: its direction is a Newton step on the face, whose
// projection may need to be shorter to lower f, and a shorter one still changes many bounds at once
// where Dostal's expansion changes one or two (docs/performance.md, "The preconditioner and the creep's solve").
bool MprgpSolver::projectedSearch(double alphaCg, std::size_t bodyCount, int threads, double& phiAp) {
  const int halvings = exact_ ? kHalvings : 0;
  for (int h = 0; h <= halvings; ++h, alphaCg *= 0.5)
    if (projectedCgStep(alphaCg, bodyCount, threads, phiAp)) return true;
  return false;
}

// Symmetric Gauss-Seidel preconditioning in face (Dostal 2009, "Optimal Quadratic Programming
// Algorithms", MPRGP with preconditioning in face): z = M_F^-1 phi with
// M_F = (I + L_F) (I + L_F^T), L_F the strictly lower part of A restricted to the free rows
// (A has a unit diagonal). That is one forward and one backward Gauss-Seidel sweep from z = 0
// over the free rows, in row order (bottom to top), on A_FF z = phi: the sweeps of nlgs without
// the projection, matrix-free through the body velocity changes of z. M_F is symmetric positive
// definite for any free set, so conjugate gradients stay conjugate gradients on the face, and it
// follows the free set with no factorisation to redo. A sweep's order is its point, so the
// rows come in blocks that share no grain (ContactRows::build()), and only those run on two threads.
double MprgpSolver::precondition(const ContactRows& rows, std::size_t bodyCount, int threads,
                                 std::optional<double> alphaCg) {
  if (exact_) return preconditionExactly(rows, bodyCount, threads, alphaCg);
  const std::size_t m = scratch_.y.size();
  // Raw pointers: with the vectors as members, the compiler reloads their data pointers after
  // every store of a double.
  double* y = scratch_.y.data();
  double* g = scratch_.g.data();
  const double* p = scratch_.p.data();
  const double* ap = scratch_.ap.data();
  double* z = scratch_.z.data();
  const SweepMass* mass = sweepMass_.data();
  const int world = static_cast<int>(bodyCount) - 1;
  // The forward sweep reads row k's own y_k and g_k only, so the conjugate gradient step can be
  // made row by row as the sweep reaches it (and z_k zeroed there), with the same values as a
  // pass of its own: one pass over y, g, p, A p and z fewer per iteration (0.97x the wall time of
  // a whole 8,000-sphere run when it was written).
  const bool step = alphaCg.has_value();
  const double alpha = alphaCg.value_or(0.0);
  // Both sweeps over the free rows; `visit(k)` updates unknown k. The rows of the two blocks
  // (ContactRows::build(): the halves of the box along x, less a strip at their edges) share no grain, so
  // the two threads sweep one each; the strip rows and the wall friction rows follow, serial.
  // Backward, the same in reverse. Either block may run first or both at once: the same bits.
  // Range b is rows [first[b], last[b]): the two blocks, then (b = 2) the serial rows.
  const std::size_t first[3] = {0, static_cast<std::size_t>(rows.sweepBlockEnd(0)),
                                static_cast<std::size_t>(rows.sweepBlockEnd(1))};
  const std::size_t last[3] = {first[1], first[2], m};
  const bool team = threads > 1 && last[1] > 0;
  // z . A p of each range, summed in the backward sweep, where each z_k takes its final value.
  double rangeZAp[3] = {0.0, 0.0, 0.0};
  // Everything by value: a closure holding references to these locals makes them escape into
  // the parallel region, and the serial sweeps then reload them from memory (10-15% slower).
  auto sweeps = [=, &rangeZAp](const auto visit) {
    const auto forward = [=](int blk) {
      for (std::size_t k = first[blk]; k < last[blk]; ++k) {
        if (step) {
          y[k] -= alpha * p[k];
          g[k] -= alpha * ap[k];
        }
        z[k] = 0.0;
        if (y[k] > 0.0) visit(k);
      }
    };
    const auto backward = [=](int blk) {
      double sum = 0.0;
      for (std::size_t k = last[blk]; k-- > first[blk];)
        if (y[k] > 0.0) {
          visit(k);
          sum += z[k] * ap[k];
        }
      return sum;
    };
    if (team) {
      onTwoThreads(forward);
    } else {
      forward(0);
      forward(1);
    }
    forward(2);
    rangeZAp[2] = backward(2);
    if (team) {
      double* sums = rangeZAp;
      onTwoThreads([=](int blk) { sums[blk] = backward(blk); });
    } else {
      rangeZAp[1] = backward(1);
      rangeZAp[0] = backward(0);
    }
  };
  if (linearOnly_) {
    scratch_.dvLinear.assign(bodyCount, Vec3::Zero());
    Vec3* dv = scratch_.dvLinear.data();
    const LinearRow* rows = linearRows_.data();
    sweeps([=](std::size_t k) {
      const LinearRow& row = rows[k];
      const double delta = g[k] - row.n.dot(dv[row.b] - dv[row.a]);
      z[k] += delta;
      dv[row.a] -= (delta * mass[k].invMa) * row.n;
      // The world's velocity never changes: no write, which both blocks would make.
      if (row.b != world) dv[row.b] += (delta * mass[k].invMb) * row.n;
    });
  } else {
    scratch_.dv.assign(bodyCount, BodyVelocity{});
    BodyVelocity* dv = scratch_.dv.data();
    const GatherRow* rows = gatherRows_.data();
    const SweepAngular* angular = sweepAngular_.data();
    sweeps([=](std::size_t k) {
      const GatherRow& row = rows[k];
      BodyVelocity& va = dv[row.a];
      BodyVelocity& vb = dv[row.b];
      const double delta = g[k] - normalVelocity(row, va, vb);
      z[k] += delta;
      va.v -= (delta * mass[k].invMa) * row.n;
      va.w -= delta * angular[k].a;
      if (row.b != world) {
        vb.v += (delta * mass[k].invMb) * row.n;
        vb.w += delta * angular[k].b;
      }
    });
  }
  const double zAp = rangeZAp[2] + rangeZAp[0] + rangeZAp[1];
  // The sweeps leave the body velocity changes of z in dv: A z costs one gather pass, which the
  // next measure() makes (with A p = A z - gamma A p).
  return zAp;
}

// The conjugate gradient step first (as the forward sweep makes it), then z on the free set after
// it; A z's body velocity changes left in scratch_.dvLinear / scratch_.dv, as the sweeps leave them.
// A failed factorisation (K_F not positive definite to round-off) hands this solve to the sweeps.
double MprgpSolver::preconditionExactly(const ContactRows& rows, std::size_t bodyCount, int threads,
                                        std::optional<double> alphaCg) {
  Scratch& s = scratch_;
  const std::size_t m = s.y.size();
  if (alphaCg) {
    const double alpha = *alphaCg;
    for (std::size_t k = 0; k < m; ++k) {
      s.y[k] -= alpha * s.p[k];
      s.g[k] -= alpha * s.ap[k];
    }
  }
  if (!freeBlock_.factor(s.y)) {
    exact_ = false;
    return precondition(rows, bodyCount, threads);
  }
  freeBlock_.apply(s.g, s.z);
  if (linearOnly_) {
    s.dvLinear.resize(bodyCount);
    applyLinearImpulses(s.z, s.dvLinear, threads);
  } else {
    s.dv.resize(bodyCount);
    applyImpulses(s.z, s.dv, threads);
  }
  return blockedSum(m, threads, s.partial, [&](std::size_t k) { return s.z[k] * s.ap[k]; });
}

// Dostal & Schoeberl (2005), "Minimizing quadratic functions subject to bound constraints with
// the rate of convergence and finite termination", Comput. Optim. Appl. 30; Dostal (2009),
// "Optimal Quadratic Programming Algorithms", Springer, algorithm MPRGP. With the free set
// F = {y_k > 0}, the free gradient phi (g on F, 0 elsewhere), the chopped gradient beta
// (min(g, 0) off F) and the reduced free gradient phi~ = min(y / alpha_bar, phi) on F, each
// iteration is one of:
//   proportional (||beta||^2 <= Gamma^2 phi~.phi): a conjugate gradient step along p if it stays
//     feasible, otherwise an expansion step (to the first bound, then a projected gradient step of
//     fixed length alpha_bar in (0, 2/||A||]) that may change the free set by many indices at once;
//     with settings.expansion = projected_cg, the projected CG step above is tried first;
//   else a proportioning step along -beta, which releases bound unknowns pulling off their bound.
// Each iteration applies A once (an expansion whose projected CG step is refused, twice), or,
// preconditioned (settings.preconditioner, the default), makes the two sweeps of precondition()
// and one gather instead of a conjugate gradient step's application of A. f decreases
// monotonically. With Dostal's expansion the method provably converges at the rate of conjugate
// gradients on the free set (sqrt of the condition number, of M_F^-1 A_FF when preconditioned in
// face) instead of Gauss-Seidel's; the projected CG expansion keeps the monotone decrease but not
// that proof, and is measured instead (projectedCgStep).
// The default preconditioner is symmetric Gauss-Seidel because it needs as few iterations as an
// incomplete Cholesky factorisation without one: no matrix, nothing redone when the free set
// changes. Near jamming the free block's soft modes form a continuum spread over the pile, which a
// coarse correction or a deflation does not remove; "cholesky" inverts the shifted free block
// exactly (preconditionExactly) in a few iterations, for a factorisation whose cost exceeds what it
// saves but on the last steps to rest, which "switching" hands to it (docs/performance.md, "The
// preconditioner and the creep's solve").
int MprgpSolver::solve(ContactRows& rows, std::vector<BodyVelocity>& vel, const NscdSettings& settings, int maxThreads,
                       const std::vector<BodyInverseMass>* bodies) {
  residual_ = 0.0;
  if (rows.rowCount() == 0) return 0;
  const std::size_t nN = rows.normalRows().size();
  const std::span<FrictionRow> frictionRows = rows.frictionRows();
  const std::size_t m = nN + frictionRows.size();
  // The team is timed against one thread and kept only while it is faster (ThreadChoice): on a
  // machine with fewer free cores than threads every pass's barrier waits for a descheduled thread,
  // which can make a team many times slower than one thread; results are the same bits either way.
  if (threadChoice_.maxThreads() != maxThreads) threadChoice_ = ThreadChoice(maxThreads);
  const int threads = m >= kParallelMin ? threadChoice_.next() : 1;
  const auto start = std::chrono::steady_clock::now();
  steps_ = MprgpSteps{};
  // "switching": sgs with a budget of iterations, unless the last solve ended on "cholesky" (then
  // "cholesky" from the start, but for every kSwitchProbeInterval-th solve, which tries sgs again).
  const bool switching = settings.preconditioner == PreconditionerKind::Switching && bodies != nullptr;
  int sgsBudget = settings.maxIterations;
  exact_ = settings.preconditioner == PreconditionerKind::Cholesky && bodies != nullptr;
  if (switching) {
    exact_ = switch_.onCholesky && ++switch_.solves % kSwitchProbeInterval != 0;
    sgsBudget = std::max(1, static_cast<int>(settings.preconditionerSwitch * static_cast<double>(nN)));
  }
  Iteration it = setUp(rows, vel, settings, threads);
  const auto buildFreeBlock = [&] {
    std::vector<JacobianRow> jacobians(m);
    for (std::size_t k = 0; k < m; ++k) {
      const GatherRow& row = gatherRows_[k];
      jacobians[k] = {row.n, row.axn, row.bxn, row.a, row.b};
    }
    freeBlock_.build(std::move(jacobians), *bodies, !linearOnly_, settings.preconditionerShift);
  };
  if (exact_) buildFreeBlock();
  int iterations = 0;
  // minimise() under the "switching" budget: past it, the rest of the solve runs on "cholesky",
  // from the iterate reached and a restarted direction.
  const auto minimiseSwitching = [&](double tolerance) {
    if (switching && !exact_) {
      iterations = minimise(it, tolerance, std::min(settings.maxIterations, sgsBudget), iterations);
      if (residual_ < tolerance || iterations < sgsBudget || iterations >= settings.maxIterations) return;
      exact_ = true;
      buildFreeBlock();
      freeGradientToP(it);
    }
    iterations = minimise(it, tolerance, settings.maxIterations, iterations);
  };
  double tangentChange = 0.0;
  const int outerCap = frictionRows.empty() ? 1 : settings.maxIterations;
  // With wall friction the normal solves inside the block iteration are inexact (Dembo-Eisenstat-
  // Steihaug style): each one to a tenth of the last tangential change, down to the tolerance, so
  // early blocks cost little.
  double innerTolerance = frictionRows.empty() ? settings.tolerance : std::max(settings.tolerance, 1e-4);
  for (int outer = 0; outer < outerCap; ++outer) {
    if (outer > 0) contactVelocities(vel, scratch_.g, threads);  // the tangential pass moved vel
    freeGradientToP(it);
    minimiseSwitching(innerTolerance);
    syncVelocities(it);
    if (frictionRows.empty()) break;
    // Block Gauss-Seidel with the tangential impulses of the wall points (their discs use the new
    // normal impulses), until a pass changes them by less than the tolerance after a normal solve
    // to the tolerance.
    const bool normalsConverged = innerTolerance <= settings.tolerance;
    tangentChange = frictionTangentPass(rows, vel, settings.frictionRelaxation);
    ++iterations;
    if ((tangentChange < settings.tolerance && normalsConverged) || iterations >= settings.maxIterations) break;
    innerTolerance = std::max(settings.tolerance, std::min(innerTolerance, 0.1 * tangentChange));
  }
  residual_ = std::max(residual_, tangentChange);
  if (switching) {
    if (exact_ != switch_.onCholesky) switch_.solves = 0;
    switch_.onCholesky = exact_;  // false also after a failed factorisation
  }
  if (exact_) {
    steps_.factorisations = freeBlock_.factorisations();
    steps_.factorUpdates = freeBlock_.updates();
  }
  // The impulses in contact order, for exportImpulses() and normalImpulse(), which read every
  // contact's points: through the rows in sweep order, each read missed the cache.
  rows.storeNormalImpulses([&](std::size_t k) { return scratch_.scale[k] * scratch_.y[k]; });
  for (std::size_t f = 0; f < frictionRows.size(); ++f)
    frictionRows[f].rn = scratch_.scale[nN + f] * scratch_.y[nN + f];
  if (m >= kParallelMin)  // time per iteration: the iteration count changes from step to step
    threadChoice_.record(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() /
                         std::max(1, iterations));
  return iterations;
}

// The unknowns at the warm start and the scaled rows; `vel` given the warm start's normal
// impulses if warmStart() left them out; Dostal's step length from the operator's bound, and
// ||b|| = ||S (H^T v_free + c)||, the gradient at r = 0, the scale of the residual. Leaves in g the
// gradient at the warm start for the first iterations.
MprgpSolver::Iteration MprgpSolver::setUp(ContactRows& rows, std::vector<BodyVelocity>& vel,
                                          const NscdSettings& settings, int threads) {
  const std::span<const NormalRow> normalRows = rows.normalRows();
  const std::span<const FrictionRow> frictionRows = rows.frictionRows();
  const std::size_t nN = normalRows.size(), m = nN + frictionRows.size();
  Scratch& s = scratch_;
  for (std::vector<double>* v : {&s.scale, &s.y, &s.y0, &s.g, &s.p, &s.ap, &s.step, &s.aStep, &s.z}) v->resize(m);
  for (std::size_t k = 0; k < nN; ++k) {
    s.scale[k] = std::sqrt(normalRows[k].invW);
    s.y[k] = normalRows[k].r / s.scale[k];
  }
  for (std::size_t f = 0; f < frictionRows.size(); ++f) {
    s.scale[nN + f] = std::sqrt(frictionRows[f].invWnn);
    s.y[nN + f] = frictionRows[f].rn / s.scale[nN + f];
  }
  buildMprgpRows(rows, vel.size());
  // warmStart() left the velocities without the normal impulses of the warm start y: applied
  // here, body by body over the scatter entries (on the team, the same bits for any team).
  if (rows.warmNormalsInSolve()) addImpulses(s.y, vel, threads);
  s.y0 = s.y;  // `vel` holds the velocities of y0; iterations move y only (see syncVelocities)
  Iteration it{rows, vel};
  it.threads = threads;
  const double bound = operatorBound_ = scaledOperatorBound(vel.size());
  it.alphaBar = bound > 0.0 ? 1.95 / bound : 1.0;  // safe: bound >= ||A||
  it.invAlphaBar = 1.0 / it.alphaBar;
  it.preconditioned = settings.preconditioner != PreconditionerKind::None;
  it.projectedCg = settings.expansion == ExpansionKind::ProjectedCg;
  contactVelocities(vel, s.g, threads);
  applyOperator(s.y, s.ap, vel.size(), threads);
  it.bNorm = std::sqrt(
      blockedSum(m, threads, s.partial, [&](std::size_t k) { return (s.g[k] - s.ap[k]) * (s.g[k] - s.ap[k]); }));
  return it;
}

// MPRGP's iterations on the normal unknowns (the tangential impulses fixed) from p = the free
// gradient, until the residual is below `tolerance` or the iterations, counted on from
// `iterations`, reach `maxIterations`; returns that count.
int MprgpSolver::minimise(Iteration& it, double tolerance, int maxIterations, int iterations) {
  constexpr double kGamma = 1.0;  // Dostal's recommended Gamma
  while (true) {
    Measures now = measure(it);
    if (it.checkDescent && !(now.gDotP > 0.0)) {  // not a descent direction: restart from phi
      freeGradientToP(it);
      now = measure(it);
    }
    it.checkDescent = false;
    residual_ = it.bNorm > 0.0 ? std::sqrt(now.projected2) / it.bNorm : 0.0;
    if (residual_ < tolerance || iterations >= maxIterations) break;
    ++iterations;
    if (now.chopped2 <= kGamma * kGamma * now.reducedFree) {
      proportionalStep(it, now);
    } else if (!proportioningStep(it, now)) {
      break;
    }
  }
  return iterations;
}

// The norms that steer the next iteration come from one blocked pass. After a conjugate gradient
// step the same pass first makes the new direction p = phi - gamma p, or p = z - gamma p with the
// preconditioner (gamma = it.conjugate), which saves a pass over y, g and p per iteration. With
// the preconditioner it also makes A p without applying A: the sweeps leave the body velocity
// changes of z, so A z is one gather, done in that pass, and A p = A z - gamma A p. That holds
// unless restricting p to the free set zeroed an entry (the free set changed): then A is applied
// afresh. A restart is the same with gamma = 0.
MprgpSolver::Measures MprgpSolver::measure(Iteration& it) {
  const std::size_t m = it.size();
  const int threads = it.threads;
  const bool preconditioned = it.preconditioned;
  const double invAlphaBar = it.invAlphaBar;
  const bool conjugateFirst = !std::isnan(it.conjugate);
  const double gamma = it.conjugate;
  it.conjugate = std::numeric_limits<double>::quiet_NaN();
  std::vector<Measures>& partial = scratch_.measures;
  const std::ptrdiff_t blocks = (static_cast<std::ptrdiff_t>(m) + kBlock - 1) / kBlock;
  partial.assign(static_cast<std::size_t>(blocks), Measures{});
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && m >= kParallelMin)
  for (std::ptrdiff_t blk = 0; blk < blocks; ++blk) {
    Measures r;
    const std::size_t end = std::min(m, static_cast<std::size_t>((blk + 1) * kBlock));
    for (std::size_t k = static_cast<std::size_t>(blk * kBlock); k < end; ++k) {
      const double g = scratch_.g[k], y = scratch_.y[k];
      if (conjugateFirst && preconditioned) {
        const double az = dvAlongRow(k);  // (A z)_k
        r.restricted = r.restricted || (gamma != 0.0 && !(y > 0.0) && scratch_.p[k] != 0.0);
        scratch_.p[k] = y > 0.0 ? scratch_.z[k] - gamma * scratch_.p[k] : 0.0;
        scratch_.ap[k] = az - gamma * scratch_.ap[k];
        r.pAp += scratch_.p[k] * scratch_.ap[k];
      } else if (conjugateFirst) {
        scratch_.p[k] = y > 0.0 ? g - gamma * scratch_.p[k] : 0.0;
      }
      const double p = scratch_.p[k];
      // Selects rather than branches (whether a row is free follows no pattern a predictor
      // could learn); the same sums and bits as branches, and, measured alone, no faster.
      const bool free = y > 0.0;
      const double chopped = !free && g < 0.0 ? g : 0.0;
      r.projected2 += free ? g * g : chopped * chopped;
      r.chopped2 += chopped * chopped;
      r.reducedFree += free ? std::min(y * invAlphaBar, g) * g : 0.0;
      r.gDotP += g * p;
    }
    partial[static_cast<std::size_t>(blk)] = r;
  }
  Measures total;
  for (const Measures& r : partial) {
    total.projected2 += r.projected2;
    total.chopped2 += r.chopped2;
    total.reducedFree += r.reducedFree;
    total.gDotP += r.gDotP;
    total.pAp += r.pAp;
    total.restricted = total.restricted || r.restricted;
  }
  if (conjugateFirst && preconditioned) {
    it.apReady = !total.restricted;
    it.pApReady = total.pAp;
  }
  return total;
}

// A proportional iteration: the conjugate gradient step along p if it stays in y >= 0, else an
// expansion (the projected CG step if settings.expansion asks for it and it lowers f, else
// Dostal's).
void MprgpSolver::proportionalStep(Iteration& it, const Measures& now) {
  const double pAp = it.apReady ? it.pApReady : applyOperator(scratch_.p, scratch_.ap, it.bodyCount(), it.threads);
  it.apReady = false;
  const double alphaCg = pAp > 0.0 ? now.gDotP / pAp : std::numeric_limits<double>::infinity();
  if (fitsBounds(it, alphaCg)) {
    conjugateGradientStep(it, alphaCg, pAp);
  } else if (double phiAp = 0.0; it.projectedCg && projectedSearch(alphaCg, it.bodyCount(), it.threads, phiAp)) {
    ++steps_.projected;  // an expansion by the projected CG step; CG goes on from it
    it.conjugate = (it.preconditioned ? precondition(it.rows, it.bodyCount(), it.threads) : phiAp) / pAp;
    it.checkDescent = true;
  } else {
    expansionStep(it);
  }
}

// Whether the step y - alpha p stays in y >= 0, tested on the very update the step makes. A
// separate pass, and no division: the largest feasible step (min y_k / p_k), taken per row in
// measure(), was the hottest instruction of that pass and about a tenth of the solve time.
// Dostal's expansion, the only user of that step length, computes it itself.
bool MprgpSolver::fitsBounds(const Iteration& it, double alpha) {
  const std::size_t m = it.size();
  const int threads = it.threads;
  const std::ptrdiff_t blocks = (static_cast<std::ptrdiff_t>(m) + kBlock - 1) / kBlock;
  int outside = 0;
#pragma omp parallel for num_threads(threads) schedule(static) \
    reduction(||                                               \
              : outside) if (threads > 1 && m >= kParallelMin)
  for (std::ptrdiff_t blk = 0; blk < blocks; ++blk) {
    const std::size_t end = std::min(m, static_cast<std::size_t>((blk + 1) * kBlock));
    int o = 0;
    for (std::size_t k = static_cast<std::size_t>(blk * kBlock); k < end; ++k)
      o |= scratch_.y[k] - alpha * scratch_.p[k] < 0.0;
    outside = outside || o;
  }
  return outside == 0;
}

// y -= alphaCg p, g -= alphaCg A p, and gamma for the next direction p <- z - gamma p (z = M_F^-1 phi,
// or phi), which the next measure() makes; preconditioned, the step itself is made by the
// forward sweep.
void MprgpSolver::conjugateGradientStep(Iteration& it, double alphaCg, double pAp) {
  if (it.preconditioned) {
    it.conjugate = precondition(it.rows, it.bodyCount(), it.threads, alphaCg) / pAp;
  } else {
    Scratch& s = scratch_;
    const double phiAp = blockedSum(it.size(), it.threads, s.partial, [&](std::size_t k) {
      s.y[k] -= alphaCg * s.p[k];
      s.g[k] -= alphaCg * s.ap[k];
      return s.y[k] > 0.0 ? s.g[k] * s.ap[k] : 0.0;
    });
    it.conjugate = phiAp / pAp;
  }
  ++steps_.conjugate;
}

// Dostal's expansion: to the first bound along -p, then a projected gradient step of length
// alpha_bar; the velocities and the gradient afresh (no drift from the recursive updates), and a
// restart of the conjugate gradients.
void MprgpSolver::expansionStep(Iteration& it) {
  ++steps_.gradient;
  const std::size_t m = it.size();
  Scratch& s = scratch_;
  double feasible = std::numeric_limits<double>::infinity();  // the first bound along -p
  for (std::size_t k = 0; k < m; ++k)
    if (s.p[k] > 0.0) feasible = std::min(feasible, s.y[k] / s.p[k]);
  for (std::size_t k = 0; k < m; ++k) {
    s.y[k] = std::max(0.0, s.y[k] - feasible * s.p[k]);
    s.g[k] -= feasible * s.ap[k];
    s.y[k] = std::max(0.0, s.y[k] - it.alphaBar * (s.y[k] > 0.0 ? s.g[k] : 0.0));
  }
  syncVelocities(it);
  contactVelocities(it.vel, s.g, it.threads);
  freeGradientToP(it);
}

// Proportioning: release the bound unknowns whose gradient pulls them off the bound, a step along
// the chopped gradient -beta; false (nothing moved) if that direction has no curvature.
bool MprgpSolver::proportioningStep(Iteration& it, const Measures& now) {
  const std::size_t m = it.size();
  Scratch& s = scratch_;
  for (std::size_t k = 0; k < m; ++k) s.step[k] = (s.y[k] > 0.0 || s.g[k] >= 0.0) ? 0.0 : s.g[k];
  const double dAd = applyOperator(s.step, s.ap, it.bodyCount(), it.threads);
  if (!(dAd > 0.0)) return false;           // a chopped direction of zero curvature: nothing to gain
  const double alpha = now.chopped2 / dAd;  // g.beta = ||beta||^2
  ++steps_.proportioning;
  for (std::size_t k = 0; k < m; ++k) {
    s.y[k] = std::max(0.0, s.y[k] - alpha * s.step[k]);
    s.g[k] -= alpha * s.ap[k];
  }
  freeGradientToP(it);
  return true;
}

// p = M_F^-1 phi (or phi): restart of the conjugate gradients.
void MprgpSolver::freeGradientToP(Iteration& it) {
  if (it.preconditioned) {
    precondition(it.rows, it.bodyCount(), it.threads);
    it.conjugate = 0.0;  // p = z, made by the next measure()
  } else {
    const std::size_t m = it.size();
    for (std::size_t k = 0; k < m; ++k) scratch_.p[k] = scratch_.y[k] > 0.0 ? scratch_.g[k] : 0.0;
  }
}

// vel <- velocities of y (vel + M^-1 H S (y - y0)), then y0 = y.
void MprgpSolver::syncVelocities(Iteration& it) {
  const std::size_t m = it.size();
  for (std::size_t k = 0; k < m; ++k) scratch_.step[k] = scratch_.y[k] - scratch_.y0[k];
  addImpulses(scratch_.step, it.vel, it.threads);
  scratch_.y0 = scratch_.y;
}

}  // namespace confpack::nscd
