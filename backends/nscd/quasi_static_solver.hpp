#pragma once
// Direct solver of one finisher step of nscd (docs/model.md, "Quasi-static compaction"): the
// frictionless contact problem from rest written for the displacement x = dq,
//     min_x  1/2 x.H x - F.x   subject to   A x >= b,
// H = diag(mu_i M_i) / h^2 (the grains' masses and world-frame inertias, each scaled by a metric
// weight mu_i >= 1), F the external forces (gravity), A the Jacobian of the gaps (one row per
// contact point: n.(dx_b + dth_b x l_b) - n.(dx_a + dth_a x l_a)), b = -gap. The multipliers are
// the contact forces.
//
// Method: augmented Lagrangian with a semismooth Newton inner solve (as in QPALM, Hermans, Themelis
// & Patrinos, Math. Prog. Comp. 14, 2022). For multipliers lambda and row penalties k_i, the inner
// problem minimises the piecewise quadratic
//     phi(x) = 1/2 x.H x - F.x + sum_i (1 / (2 k_i)) max(0, lambda_i - k_i (A_i x - b_i))^2,
// whose generalised Newton step solves (H + A_S^T K A_S) dx = -grad phi on the rows S where the
// bracket is positive; the outer step sets lambda_i <- max(0, lambda_i - k_i (A_i x - b_i)).
// Why not MPRGP here: MPRGP's iterations grow with the conditioning of the Delassus operator, which
// near jamming (and with spread metric weights) is poor; a sparse Cholesky factorisation does not
// care. k_i = kPenalty / W_ii (W_ii = A_i H^-1 A_i^T, the row's Delassus diagonal) makes the penalty
// scale free; the outer iteration then converges at a rate of about 1 / kPenalty per step.
// The factorisation is Eigen's SimplicialLDLT with an AMD ordering (header-only, already a
// dependency); the pattern of A^T A is analysed once per step and refactorised per Newton iteration.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <vector>

#include "backends/nscd/narrow_phase.hpp"
#include "core/box.hpp"

namespace confpack::nscd {

class QuasiStaticSolver {
 public:
  /// One grain as the solver sees it.
  struct Body {
    double mass = 0.0;                       ///< mu_i m_i
    core::Mat3 inertia = core::Mat3::Zero(); ///< mu_i I_i, world frame about the centroid
    core::Vec3 force = core::Vec3::Zero();   ///< external force (gravity) [rho g d_L^3]
  };
  struct Outcome {
    int newtonIterations = 0;
    int outerIterations = 0;
    double infeasibility = 0.0;  ///< max_i max(0, b_i - A_i x) at the end [d_L]
    bool converged = false;
  };

  /// Solves the step: `positions` are the grains' centroids, `contacts` the detected contacts,
  /// `warmForces` one force per point in contact order (cached, may be empty: all zero).
  /// `rotations`: whether grains have rotational degrees of freedom (false for spheres, whose
  /// frictionless contacts exert no moment). On return `displacement` and `rotation` hold dq per
  /// grain and `forces` the force of each contact point, in contact order.
  Outcome solve(const std::vector<ContactGeometry>& contacts, const std::vector<core::Vec3>& positions,
                const std::vector<Body>& bodies, const core::BoxDef& box, bool rotations, double h,
                const std::vector<double>& warmForces, std::vector<core::Vec3>& displacement,
                std::vector<core::Vec3>& rotation, std::vector<double>& forces);

 private:
  void buildRows(const std::vector<ContactGeometry>& contacts, const std::vector<core::Vec3>& positions,
                 const core::BoxDef& box, bool rotations, std::size_t bodyCount);

  Eigen::SparseMatrix<double> a_;  // m x ndof, row-major build via triplets
  Eigen::SparseMatrix<double> h_;  // ndof x ndof, block diagonal
  Eigen::VectorXd b_, f_, k_, lambda_, x_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt_;
  std::vector<Eigen::Triplet<double>> triplets_;
};

}  // namespace confpack::nscd
