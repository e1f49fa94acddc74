#pragma once
// Nonlinear Gauss-Seidel on contact impulses, the "nlgs" solver of contact_solver.hpp
// (Moreau 1994; Jean 1999 "The non-smooth contact dynamics method", CMAME 177; LMGC90's NLGS),
// over the rows of contact_rows.hpp, which state the contact law it solves.
//
// Gauss-Seidel update of one row (a few dozen flops, Jacobian pieces precomputed):
//     r_n <- max(0, r_n - omega (u_n + c) / W_nn)      (omega = 1: plain Gauss-Seidel; option)
// and for a friction point, after its normal update, in the same visit,
//     r_t <- proj_{||r_t|| <= mu r_n} ( r_t - u_t / w_t ),   w_t = largest eigenvalue of W_tt.
// A scalar w_t (not W_tt^-1) keeps the fixed point exactly Coulomb's law: on the disc boundary,
// u_t = -(lambda - 1) w_t r_t is anti-parallel to r_t; inside, u_t = 0.
//
// Convergence ("Quad"-type relative norm over one sweep k):
//     eps_k = sqrt( sum_rows ||r^k - r^(k-1)||^2 / sum_rows ||r^k||^2 ),
// stop when eps_k < tolerance (after min_iterations) or after max_iterations sweeps.
// The stopping rule stays the impulse norm above: a rule on the largest velocity error per row
// (|u_n + c| below 3e-4 g dt) stopped earlier (1270 versus 1900 sweeps per step) but left
// max |sum F| / (d^2 P) at 1e-3 to 3e-3 instead of 2e-4 to 1.5e-3 (both at omega = 1.85, same pile
// restarted at rest, t + 8 to t + 27): near jamming W is ill-conditioned,
// so a small H^T dv does not bound the impulse (force) error.
#include <vector>

#include "backends/nscd/contact_rows.hpp"
#include "backends/nscd/nscd_settings.hpp"

namespace confpack::nscd {

/// Gauss-Seidel sweeps over the rows of a ContactRows, bottom to top, each row projected on its
/// law. Owns no scratch (the impulses it updates are the rows'), only the residual of its last
/// solve. Verb: solve.
class NlgsSolver {
 public:
  /// Sweeps the rows until eps_k < settings.tolerance (after settings.minIterations sweeps) or
  /// settings.maxIterations sweeps, updating the rows' impulses and `velocities` (v_free plus the
  /// warm start on entry, v_{i+1} on exit), then stores the normal impulses in the rows in
  /// contact order; returns the number of sweeps (0 without rows).
  int solve(ContactRows& rows, std::vector<BodyVelocity>& velocities, const NscdSettings& settings);
  /// eps_k of the last sweep of the last solve (0 without rows).
  double residual() const { return residual_; }

 private:
  double residual_ = 0.0;
};

}  // namespace confpack::nscd
