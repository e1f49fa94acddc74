#pragma once
// A primal-dual interior-point method over the contact rows, the "ipm" solver of
// contact_solver.hpp, for the contact law stated in contact_rows.hpp; ipm_solver.cpp states the
// algorithm.
//
// The step's frictionless contact problem is the convex quadratic program in the velocity change
// x = v - v_free of the bodies that carry a row
//     min 1/2 x.M x   subject to   s = J x + b >= 0,   b = J v_free + c,
// whose multipliers are the normal impulses r >= 0 and whose optimality conditions are the
// Signorini law (M x = J^T r, s >= 0, r >= 0, s r = 0). MPRGP (mprgp_solver.hpp) solves its dual
// over r and needs iterations that grow like the square root of the condition number of the
// Delassus operator W = J M^-1 J^T, which near jamming is huge: a nearly isostatic pile has soft
// collective modes (the whole column settling) whose impulses a Krylov method resolves last.
// Mehrotra's predictor-corrector needs a number of iterations (20 to 40) that does not depend on
// that conditioning; each solves the Newton system
//     (M + J^T D J) dx = rhs,   D = diag(r / s),
// whose sparsity is the contact graph, by a sparse Cholesky factorisation (CHOLMOD's supernodal
// LLT through Eigen's CholmodSupport: its dense blocks run at BLAS speed, and a finisher step
// took half the time of CHOLMOD's simplicial factorisation; docs/performance.md).
// Side-wall friction is handled as MPRGP does it: block Gauss-Seidel between the normal problem
// (here by the interior-point method, tangential impulses fixed) and one projected pass over the
// tangential impulses.
#include <memory>
#include <vector>

#include "backends/nscd/contact_rows.hpp"
#include "backends/nscd/nscd_settings.hpp"

namespace confpack::nscd {

/// Mehrotra's primal-dual interior-point method on the normal impulses of a ContactRows (with a
/// tangential pass for side-wall friction, in block Gauss-Seidel). Owns its scratch (the rows'
/// Jacobians, the body map, the Newton system and its factorisation) and what its last solve
/// measured. Verb: solve.
class IpmSolver {
 public:
  IpmSolver();
  ~IpmSolver();
  IpmSolver(IpmSolver&&) noexcept;
  IpmSolver& operator=(IpmSolver&&) noexcept;

  /// Solves the rows' contact problem for bodies of inverse masses `bodies` (one per body, the
  /// last the static world), updating `velocities` (v_free plus the tangential warm start on
  /// entry, v_{i+1} on exit) and the rows' impulses; returns the number of interior-point
  /// iterations (each one factorisation), plus the tangential passes with wall friction.
  int solve(ContactRows& rows, const std::vector<BodyInverseMass>& bodies, std::vector<BodyVelocity>& velocities,
            const NscdSettings& settings);
  /// The residual of the last solve, measured as MPRGP's: the projected gradient of the dual
  /// problem at the returned impulses, relative to its value at r = 0 (or the last tangential
  /// change, if larger); 0 without rows.
  double residual() const { return residual_; }

 private:
  struct Impl;  // the factorisation's types stay out of this header
  std::unique_ptr<Impl> impl_;
  double residual_ = 0.0;
};

}  // namespace confpack::nscd
