#pragma once
// Contact solver of the nscd backend: nonlinear Gauss-Seidel or MPRGP on contact impulses
// (Moreau 1994; Jean 1999 "The non-smooth contact dynamics method", CMAME 177; LMGC90's NLGS).
// The problem it solves (unknowns, Delassus operator, Signorini and Coulomb laws) and the rows
// that state it, with their sweep order and blocks, are in contact_rows.hpp.
//
// Parts with fixed verbs, after Jolt's constraint parts:
//   ContactRows  (contact_rows.hpp)  the step's rows: build, warmStart, exportImpulses, and the
//                                    impulses, row count and sweep blocks they hold;
//   NlgsSolver   (nlgs_solver.hpp)   nonlinear Gauss-Seidel over the rows: solve;
//   MprgpSolver  (mprgp_solver.hpp)  MPRGP over the rows: solve;
//   IpmSolver    (ipm_solver.hpp)    a primal-dual interior-point method over the rows: solve.
// ContactSolver holds the rows and the three solvers, and its solve() dispatches on
// NscdSettings::solver.
//
// Three solvers of the same problem (NscdSettings::solver); the first two are the dynamic
// steps' choice, the third the quasi-static finisher's for sphere piles (NscdSettings::finisherSolver):
// - "nlgs" (nlgs_solver.hpp), nonlinear Gauss-Seidel (LMGC90's NLGS). Cheap per sweep
//   and robust, but its error near jamming shrinks by a factor close to 1 per sweep (the Delassus
//   matrix of a jammed, nearly isostatic pile is ill-conditioned): it stops on a small change per
//   sweep while the impulses are still far from the solution, and that error is a force imbalance
//   on every grain.
// - "mprgp" (default; mprgp_solver.hpp): the frictionless part as a convex quadratic program over
//   r >= 0, solved by Dostal's MPRGP. Iterations grow like the square root of the condition number
//   instead of linearly, and the stopping rule is the true residual of the law. On a 493-sphere
//   pile it reaches equilibrium where nlgs stays at a force ratio of 2.5e-3 (docs/performance.md,
//   "Why MPRGP and not Gauss-Seidel").
// - "ipm" (ipm_solver.hpp): the same program in primal form by Mehrotra's predictor-corrector,
//   each iteration a sparse Cholesky factorisation, then an exact solve on the closed contacts.
//   Its 20 to 35 iterations do not depend on the conditioning, which is what the finisher's long
//   steps from rest need; a warm-started dynamic step needs only a few cheap MPRGP iterations.
#include <array>
#include <vector>

#include "backends/nscd/contact_cache.hpp"
#include "backends/nscd/contact_rows.hpp"
#include "backends/nscd/ipm_solver.hpp"
#include "backends/nscd/mprgp_solver.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nlgs_solver.hpp"
#include "backends/nscd/nscd_settings.hpp"

namespace confpack::nscd {

/// The contact solve of one step: the rows (ContactRows) and the three solvers of them (NlgsSolver,
/// MprgpSolver, IpmSolver). Owns one of each and the residual of the last solve. Verbs, in step order:
/// prepare, warmStart, solve, exportImpulses; the accessors read the rows or the last MPRGP solve.
class ContactSolver {
 public:
  /// Builds the rows of every contact point for settings.solver (ContactRows::build).
  void prepare(const std::vector<ContactGeometry>& contacts, const std::vector<core::Vec3>& positions,
               const std::vector<BodyInverseMass>& bodies, const core::BoxDef& box, const core::WallMaterial& walls,
               double dt, const NscdSettings& settings) {
    rows_.build(contacts, positions, bodies, box, walls, dt, settings);
    bodies_ = &bodies;
  }
  /// Sets the impulses from the cache and applies them to the velocities (ContactRows::warmStart);
  /// with mprgp (the solver of the last prepare()), only the tangential ones: solve() applies the
  /// normal impulses in its own pass over the bodies.
  void warmStart(const ContactCache& cache, const std::vector<ContactGeometry>& contacts, double dt,
                 std::vector<BodyVelocity>& velocities) {
    rows_.warmStart(cache, contacts, dt, velocities);
  }
  /// Solves the step's contact problem with settings.solver, updating `velocities` (v_free plus
  /// the warm start on entry, v_{i+1} on exit); returns the number of iterations: Gauss-Seidel
  /// sweeps (nlgs), operator applications W p (mprgp, each about two sweeps of work) or
  /// factorisations (ipm: interior-point iterations and polish rounds, plus tangential passes).
  /// `maxThreads` bounds MPRGP's team (MprgpSolver::solve); the other solvers run on one thread.
  int solve(std::vector<BodyVelocity>& velocities, const NscdSettings& settings, int maxThreads = 1);
  double residual() const { return residual_; }
  /// The grains touched by the rows of each of the two sweep blocks of the last prepare()
  /// (ContactRows::sweepBlockBodies).
  std::array<std::vector<int>, 2> sweepBlockBodies(int world) const { return rows_.sweepBlockBodies(world); }
  using MprgpSteps = nscd::MprgpSteps;
  /// What the MPRGP iterations of the last MPRGP solve were.
  const MprgpSteps& mprgpSteps() const { return mprgp_.steps(); }
  /// The upper bound of ||S W S|| of the last MPRGP solve (MprgpSolver::operatorBound); 0 before any.
  double operatorBound() const { return mprgp_.operatorBound(); }
  /// The "switching" preconditioner's state (MprgpSolver::switchState), for checkpoints.
  SwitchState switchState() const { return mprgp_.switchState(); }
  void setSwitchState(SwitchState state) { mprgp_.setSwitchState(state); }
  int rowCount() const { return rows_.rowCount(); }
  /// The rows of the last prepare(), as the solvers see them (a block's dump, bench/microbench.hpp).
  const ContactRows& rows() const { return rows_; }

  /// Impulses of contact c, point p, after solve(): normal and tangential (world vector).
  double normalImpulse(int c, int p) const { return rows_.normalImpulse(c, p); }
  core::Vec3 tangentImpulse(int c, int p) const { return rows_.tangentImpulse(c, p); }
  /// Writes the solution into cache entries (same order as the contacts).
  void exportImpulses(const std::vector<ContactGeometry>& contacts, std::vector<CachedContact>& out) const {
    rows_.exportImpulses(contacts, out);
  }

 private:
  ContactRows rows_;
  NlgsSolver nlgs_;
  MprgpSolver mprgp_;
  IpmSolver ipm_;
  const std::vector<BodyInverseMass>* bodies_ = nullptr;  // of the last prepare(), for ipm
  double residual_ = 0.0;
};

}  // namespace confpack::nscd
