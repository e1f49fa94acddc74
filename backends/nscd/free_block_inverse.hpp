#pragma once
// The "cholesky" preconditioner of MPRGP (mprgp_solver.hpp): the exact inverse of the shifted free
// block, (A_FF + eps I)^-1, applied through a sparse Cholesky factorisation in body space.
//
// MPRGP's operator is A = G M^-1 G^T, G = S J the scaled Jacobian of the normal unknowns on the
// mobile bodies' velocities, M their masses and world-frame inertias. By the Woodbury identity
//     (A_FF + eps I)^-1 = (I - G_F K_F^-1 G_F^T) / eps,    K_F = eps M + G_F^T G_F,
// where K_F is a body-space matrix (3 unknowns a grain for spheres, 6 otherwise) with a block per
// grain and per touching pair: a contact network's stiffness, which CHOLMOD factors with little
// fill, where A_FF itself (a row per contact point, coupled to every row on its two grains) fills
// in badly (a sparse LDL^T of it filled about n^2).
// Why an exact inverse and not a multigrid: near jamming the soft modes of A_FF form a continuum
// with no gap (a 1,648-sphere creep block: lambda_1 = 1.2e-4, lambda_100 = 4.3e-3, ||A|| = 3.1,
// each mode spread over 2 to 13 % of the rows), which neither Gauss-Seidel sweeps (545 conjugate
// gradient iterations to 1e-10) nor a smoothed-aggregation multigrid on A (439) resolve. Under
// (A_FF + eps I)^-1 every eigenvalue lambda of A_FF becomes lambda / (lambda + eps): those above
// eps are all but 1, and conjugate gradients need 6 (eps = 1e-5) to 12 (1e-4) iterations.
// Units: A is dimensionless (unit diagonal), so is eps; the body-space matrix is in the units of
// M [m = rho V, rho = 1] and of G^T G, which are the same after the scaling S.
#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "backends/nscd/contact_rows.hpp"

namespace confpack::nscd {

/// One normal unknown's scaled Jacobian: u = n.(v_b - v_a) + bxn.w_b - axn.w_a (b may be a body
/// that does not move, the world or a fixed grain, which then has no unknowns).
struct JacobianRow {
  core::Vec3 n, axn, bxn;
  int a = 0, b = 0;
};

/// The factor of K_F = eps M + G_F^T G_F for one free set F of a solve's rows, and the products
/// with (A_FF + eps I)^-1 it gives. Owns the matrix, its symbolic analysis (once per set of rows,
/// every row in the pattern, so that a new free set costs a numeric factorisation only) and the
/// factor. Verbs, in order: build, factor, apply.
class FreeBlockInverse {
 public:
  FreeBlockInverse();
  ~FreeBlockInverse();
  FreeBlockInverse(FreeBlockInverse&&) noexcept;
  FreeBlockInverse& operator=(FreeBlockInverse&&) noexcept;

  /// Takes a solve's rows and the inverse masses of its bodies (a body of zero inverse mass does
  /// not move and gets no unknowns); `angular`: whether some row turns a body (6 unknowns a body
  /// instead of 3); `shift`: eps > 0. Forgets the last factor. The rows are kept (moved in).
  void build(std::vector<JacobianRow> rows, const std::vector<BodyInverseMass>& bodies, bool angular, double shift);
  /// Factors K_F for F = {k : y[k] > 0}, unless the factor already holds that set; false if the
  /// factorisation failed (then apply() must not be called).
  bool factor(std::span<const double> y);
  /// z_F = (A_FF + eps I)^-1 phi_F and z = 0 off F, F the set of the last factor(), phi = g on F.
  void apply(std::span<const double> g, std::span<double> z);
  /// Factorisations afresh, and low-rank modifications of the factor, since build().
  int factorisations() const { return factorisations_; }
  int updates() const { return updates_; }
  /// Most rows whose change of free set is made as an update or downdate of the factor [-]; more,
  /// and the factor is made afresh.
  static constexpr std::size_t kRefactorRows = 256;

 private:
  struct Impl;  // the factorisation's types stay out of this header
  std::unique_ptr<Impl> impl_;
  int factorisations_ = 0, updates_ = 0;
};

}  // namespace confpack::nscd
