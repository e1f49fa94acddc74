// (A_FF + eps I)^-1 through K_F = eps M + G_F^T G_F (free_block_inverse.hpp states the identity).
#include "backends/nscd/free_block_inverse.hpp"

#include <cholmod.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <cstddef>
#include <utility>

#include "backends/nscd/thread_choice.hpp"
#include "core/blas_lock.hpp"

namespace confpack::nscd {

using core::Mat3;
using core::Vec3;

namespace {

/// Row k's Jacobian on one of its bodies: 3 linear entries, then 3 angular ones.
using BodyJacobian = Eigen::Matrix<double, 6, 1>;

BodyJacobian onBody(const JacobianRow& row, bool onB) {
  BodyJacobian u;
  u.head<3>() = onB ? row.n : Vec3(-row.n);
  u.tail<3>() = onB ? row.bxn : Vec3(-row.axn);
  return u;
}

}  // namespace

// The matrix and factor through CHOLMOD's C interface, not Eigen's wrapper: a change of the free
// set by a few rows is a low-rank update or downdate of the factor (cholmod_updown), which the
// wrapper does not expose. Every row is in K's pattern, with zero weight off the free set, so
// that the symbolic analysis serves every free set of a solve.
struct FreeBlockInverse::Impl {
  Impl() {
    cholmod_start(&common);
    common.print = 0;  // a failure is reported through the return values
    // A factor afresh is supernodal (its dense blocks at BLAS speed: 21 ms against 117 ms simplicial
    // on a 1,648-sphere creep block); cholmod_updown turns it into the simplicial LDL^T it modifies.
    common.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~Impl() {
    if (factor) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  std::vector<JacobianRow> rows;
  std::vector<int> unknown;  // body -> its first unknown in K, or -1 if it does not move
  int dof = 3;
  int size = 0;
  double shift = 0.0;
  std::vector<Eigen::Triplet<double>> mass;  // eps M (lower triangle)
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> k;
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  std::vector<int> permutedRow;  // unknown -> its row in the factor's ordering
  std::vector<char> free;        // the free set the factor holds (empty: none)
  std::vector<int> added, removed;
  Eigen::VectorXd bodySide, solved;

  // The entries of g_k^T g_k (lower triangle of K), times `weight` (0 keeps the pattern only).
  void addRow(const JacobianRow& row, double weight) {
    const int ua = unknown[static_cast<std::size_t>(row.a)], ub = unknown[static_cast<std::size_t>(row.b)];
    const BodyJacobian ja = onBody(row, false), jb = onBody(row, true);
    const auto block = [&](int ui, const BodyJacobian& ji, int uj, const BodyJacobian& jj) {
      for (int r = 0; r < dof; ++r)
        for (int c = 0; c < dof; ++c)
          if (ui + r >= uj + c) triplets.emplace_back(ui + r, uj + c, weight * ji[r] * jj[c]);
    };
    if (ua >= 0) block(ua, ja, ua, ja);
    if (ub >= 0) block(ub, jb, ub, jb);
    if (ua >= 0 && ub >= 0) {
      if (ua > ub)
        block(ua, ja, ub, jb);
      else
        block(ub, jb, ua, ja);
    }
  }
  // Analyses and factors K for the free set `free` (every row in the pattern); false if it failed.
  bool factorAfresh() {
    triplets.assign(mass.begin(), mass.end());
    for (std::size_t i = 0; i < rows.size(); ++i) addRow(rows[i], free[i] ? 1.0 : 0.0);
    k.resize(size, size);
    k.setFromTriplets(triplets.begin(), triplets.end());
    k.makeCompressed();
    cholmod_sparse view{};
    view.nrow = view.ncol = static_cast<std::size_t>(size);
    view.nzmax = static_cast<std::size_t>(k.nonZeros());
    view.p = k.outerIndexPtr();
    view.i = k.innerIndexPtr();
    view.x = k.valuePtr();
    view.stype = -1;  // the lower triangle of a symmetric matrix
    view.itype = CHOLMOD_INT;
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    view.sorted = 1;
    view.packed = 1;
    if (factor) cholmod_free_factor(&factor, &common);
    factor = cholmod_analyze(&view, &common);
    if (!factor || !cholmod_factorize(&view, factor, &common) || factor->minor < factor->n) return false;
    const int* perm = static_cast<const int*>(factor->Perm);
    permutedRow.assign(static_cast<std::size_t>(size), 0);
    for (int r = 0; r < size; ++r) permutedRow[static_cast<std::size_t>(perm[r])] = r;
    return true;
  }
  // L D L^T +- C C^T, C's columns the rows `changed` in the factor's ordering; false if it failed.
  bool modify(const std::vector<int>& changed, bool update) {
    if (changed.empty()) return true;
    cholmod_sparse* c =
        cholmod_allocate_sparse(static_cast<std::size_t>(size), changed.size(),
                                changed.size() * 2 * static_cast<std::size_t>(dof), 1, 1, 0, CHOLMOD_REAL, &common);
    if (!c) return false;
    int* cp = static_cast<int*>(c->p);
    int* ci = static_cast<int*>(c->i);
    double* cx = static_cast<double*>(c->x);
    std::vector<std::pair<int, double>> column;
    int nz = 0;
    for (std::size_t col = 0; col < changed.size(); ++col) {
      cp[col] = nz;
      const JacobianRow& row = rows[static_cast<std::size_t>(changed[col])];
      column.clear();
      for (const bool onB : {false, true}) {
        const int u = unknown[static_cast<std::size_t>(onB ? row.b : row.a)];
        if (u < 0) continue;
        const BodyJacobian j = onBody(row, onB);
        for (int d = 0; d < dof; ++d)
          if (j[d] != 0.0) column.emplace_back(permutedRow[static_cast<std::size_t>(u + d)], j[d]);
      }
      std::sort(column.begin(), column.end());
      for (const auto& [r, v] : column) {
        ci[nz] = r;
        cx[nz++] = v;
      }
    }
    cp[changed.size()] = nz;
    const bool ok = cholmod_updown(update ? 1 : 0, c, factor, &common) && factor->minor == factor->n;
    cholmod_free_sparse(&c, &common);
    return ok;
  }
};

FreeBlockInverse::FreeBlockInverse() : impl_(std::make_unique<Impl>()) {}
FreeBlockInverse::~FreeBlockInverse() = default;
FreeBlockInverse::FreeBlockInverse(FreeBlockInverse&&) noexcept = default;
FreeBlockInverse& FreeBlockInverse::operator=(FreeBlockInverse&&) noexcept = default;

void FreeBlockInverse::build(std::vector<JacobianRow> rows, const std::vector<BodyInverseMass>& bodies, bool angular,
                             double shift) {
  Impl& p = *impl_;
  p.rows = std::move(rows);
  p.dof = angular ? 6 : 3;
  p.shift = shift;
  // Unknowns for the moving bodies that carry a row, in body order.
  std::vector<char> used(bodies.size(), 0);
  for (const JacobianRow& row : p.rows)
    used[static_cast<std::size_t>(row.a)] = used[static_cast<std::size_t>(row.b)] = 1;
  p.unknown.assign(bodies.size(), -1);
  p.size = 0;
  p.mass.clear();
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    if (!used[b] || !(bodies[b].invMass > 0.0)) continue;
    p.unknown[b] = p.size;
    for (int i = 0; i < 3; ++i) p.mass.emplace_back(p.size + i, p.size + i, shift / bodies[b].invMass);
    if (angular) {
      const Mat3 inertia = bodies[b].invInertia.inverse();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c <= r; ++c) p.mass.emplace_back(p.size + 3 + r, p.size + 3 + c, shift * inertia(r, c));
    }
    p.size += p.dof;
  }
  p.free.clear();
  if (p.factor) cholmod_free_factor(&p.factor, &p.common);
  factorisations_ = updates_ = 0;
}

bool FreeBlockInverse::factor(std::span<const double> y) {
  Impl& p = *impl_;
  const DynamicOpenMpTeams dynamicTeams;
  const auto lock = core::blasLock();
  if (p.factor && p.free.size() == y.size()) {
    p.added.clear();
    p.removed.clear();
    for (std::size_t i = 0; i < y.size(); ++i) {
      const bool now = y[i] > 0.0;
      if (now == (p.free[i] != 0)) continue;
      (now ? p.added : p.removed).push_back(static_cast<int>(i));
      p.free[i] = now;
    }
    const std::size_t changes = p.added.size() + p.removed.size();
    if (changes == 0) return true;
    // A few rows: update and downdate the factor; many: factor afresh (on a 1,648-sphere block a
    // factorisation cost 21 ms and a change of a few rows 4 ms; kRefactorRows is not tuned).
    if (changes <= kRefactorRows) {
      ++updates_;
      if (p.modify(p.added, true) && p.modify(p.removed, false)) return true;
    }
  } else {
    p.free.resize(y.size());
    for (std::size_t i = 0; i < y.size(); ++i) p.free[i] = y[i] > 0.0;
  }
  ++factorisations_;
  if (p.factorAfresh()) return true;
  p.free.clear();
  return false;
}

void FreeBlockInverse::apply(std::span<const double> g, std::span<double> z) {
  Impl& p = *impl_;
  const std::size_t m = p.rows.size();
  // t = G_F^T phi_F, in body space.
  p.bodySide.setZero(p.size);
  for (std::size_t i = 0; i < m; ++i) {
    if (!p.free[i]) continue;
    const JacobianRow& row = p.rows[i];
    for (const bool onB : {false, true}) {
      const int u = p.unknown[static_cast<std::size_t>(onB ? row.b : row.a)];
      if (u < 0) continue;
      const BodyJacobian j = onBody(row, onB);
      for (int d = 0; d < p.dof; ++d) p.bodySide[u + d] += g[i] * j[d];
    }
  }
  {
    const auto lock = core::blasLock();
    cholmod_dense side{};
    side.nrow = side.d = side.nzmax = static_cast<std::size_t>(p.size);
    side.ncol = 1;
    side.x = p.bodySide.data();
    side.xtype = CHOLMOD_REAL;
    side.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, p.factor, &side, &p.common);
    p.solved = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(x->x), p.size);
    cholmod_free_dense(&x, &p.common);
  }
  // z_F = (phi_F - G_F K_F^-1 t) / eps.
  const double invShift = 1.0 / p.shift;
  for (std::size_t i = 0; i < m; ++i) {
    if (!p.free[i]) {
      z[i] = 0.0;
      continue;
    }
    const JacobianRow& row = p.rows[i];
    double gu = 0.0;
    for (const bool onB : {false, true}) {
      const int u = p.unknown[static_cast<std::size_t>(onB ? row.b : row.a)];
      if (u < 0) continue;
      const BodyJacobian j = onBody(row, onB);
      for (int d = 0; d < p.dof; ++d) gu += j[d] * p.solved[u + d];
    }
    z[i] = (g[i] - gu) * invShift;
  }
}

}  // namespace confpack::nscd
