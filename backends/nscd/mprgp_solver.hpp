#pragma once
// MPRGP over the contact rows, the "mprgp" solver of contact_solver.hpp (the default), for the
// contact law stated in contact_rows.hpp; mprgp_solver.cpp states the algorithm.
//
// The frictionless part is the convex quadratic program  min 1/2 r.W r + r.(u_free + c)  over
// r >= 0, whose optimality conditions are exactly the Signorini law (contact_rows.hpp); it is
// solved by Dostal's MPRGP, conjugate gradients with gradient projections for the bounds (after
// LMGC90's conjugate-gradient solvers, Renouf & Alart 2004). Iterations grow like the square root
// of the condition number instead of linearly, and the stopping rule is the true residual of the
// law. Its conjugate gradients are preconditioned on the free set by a forward and a backward
// Gauss-Seidel sweep (NscdSettings::preconditioner): the sweeps of nlgs serve inside MPRGP, where
// they cut the iterations 2.5 to 3.5 times. For two threads they run over blocks of rows that
// share no grain (contact_rows.hpp). Or ("cholesky", free_block_inverse.hpp) by the shifted free
// block's exact inverse, with projected steps searched back by halves. Or ("switching") by the
// sweeps until a solve has taken a budget of iterations, then by the exact inverse.
// Wall friction (Coulomb, not a quadratic program) is handled by block Gauss-Seidel: MPRGP on
// every normal impulse with the tangential ones fixed, then one projected pass over the
// tangential impulses, over-relaxed by NscdSettings::frictionRelaxation, until both have
// converged.
#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

#include "backends/nscd/contact_rows.hpp"
#include "backends/nscd/free_block_inverse.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "backends/nscd/thread_choice.hpp"

namespace confpack::nscd {

/// What the MPRGP iterations of the last solve were (their sum is its iteration count, less the
/// tangential passes with wall friction).
struct MprgpSteps {
  int conjugate = 0;       ///< conjugate gradient steps
  int projected = 0;       ///< expansions by a projected conjugate gradient step
  int gradient = 0;        ///< expansions by Dostal's step (first bound, then projected gradient)
  int proportioning = 0;   ///< proportioning steps (release of bound unknowns)
  int factorisations = 0;  ///< "cholesky" preconditioner: factorisations afresh
  int factorUpdates = 0;   ///< "cholesky" preconditioner: updates and downdates for a changed free set
};

/// What a "switching" preconditioner carries from one solve to the next (its choice for the next).
struct SwitchState {
  bool onCholesky = false;  ///< the last solve ended on "cholesky"
  int solves = 0;           ///< solves started on "cholesky" since it switched (every 16th tries "sgs")
};

/// Dostal's MPRGP on the normal impulses of a ContactRows (with a tangential pass for side-wall
/// friction, in block Gauss-Seidel), in the scaled unknowns y = r / s. Owns its scratch (the
/// unknowns, gradient, directions, compact gather and scatter copies of the rows, body velocity
/// changes), its choice of team, and what its last solve measured: residual, step statistics
/// (MprgpSteps) and operator bound. Verb: solve.
class MprgpSolver {
 public:
  /// Solves the rows' contact problem, updating `velocities` (v_free plus the warm start on entry,
  /// without its normal impulses if rows.warmNormalsInSolve(); v_{i+1} on exit) and the rows'
  /// impulses, and stores the normal impulses in the rows in contact order; returns the number of
  /// iterations: operator applications W p (each about two sweeps of work), plus the tangential
  /// passes with wall friction (0 without rows).
  /// `maxThreads` (the run's threads, SystemDef::threads): the most its passes run on; each solve
  /// times the team against one thread and keeps the faster (thread_choice.hpp), to the same bits.
  /// `bodies` (the inverse masses, the last the static world) serve the "cholesky" preconditioner;
  /// without them it falls back on "sgs".
  int solve(ContactRows& rows, std::vector<BodyVelocity>& velocities, const NscdSettings& settings, int maxThreads = 1,
            const std::vector<BodyInverseMass>* bodies = nullptr);
  /// The residual of the last solve: the projected gradient relative to ||b|| (or the last
  /// tangential change, if larger); 0 without rows.
  double residual() const { return residual_; }
  /// What the iterations of the last solve were.
  const MprgpSteps& steps() const { return steps_; }
  /// The upper bound of ||S W S|| (S = diag(W_kk^-1/2)) that set the expansion step of the last
  /// MPRGP solve (alpha_bar = 1.95 / bound); 0 before any.
  double operatorBound() const { return operatorBound_; }
  /// The "switching" preconditioner's state, which a checkpoint keeps so that a resumed run takes
  /// the same steps.
  SwitchState switchState() const { return switch_; }
  void setSwitchState(SwitchState state) { switch_ = state; }

 private:
  // Building blocks over the normal unknowns (frictionless rows, then the normal part of the
  // friction rows), in the scaled variables y = r / s (s = W_nn^-1/2).
  void buildMprgpRows(const ContactRows& rows, std::size_t bodyCount);
  // Body velocity changes M^-1 H S y: all parts, or linear only (linearOnly_).
  void applyImpulses(const std::vector<double>& y, std::vector<BodyVelocity>& out, int threads) const;
  void applyLinearImpulses(const std::vector<double>& y, std::vector<core::Vec3>& out, int threads) const;
  // vel += M^-1 H S y.
  void addImpulses(const std::vector<double>& y, std::vector<BodyVelocity>& vel, int threads);
  // out = S (H^T vel + bias): the scaled gradient of the step's quadratic program at vel.
  double contactVelocities(const std::vector<BodyVelocity>& vel, std::vector<double>& out, int threads);
  // out = A x (A = S W S); returns x . A x.
  double applyOperator(const std::vector<double>& x, std::vector<double>& out, std::size_t bodyCount, int threads);
  double scaledOperatorBound(std::size_t bodyCount);
  bool projectedCgStep(double alphaCg, std::size_t bodyCount, int threads, double& phiAp);
  static constexpr int kHalvings = 4;
  bool projectedSearch(double alphaCg, std::size_t bodyCount, int threads, double& phiAp);
  // z = M_F^-1 g on the free set F = {y > 0} (0 elsewhere), M_F the symmetric Gauss-Seidel
  // splitting of A restricted to F, leaving M^-1 H S z in scratch_.dvLinear / scratch_.dv; returns z . scratch_.ap.
  // Given alphaCg, the forward sweep first makes the conjugate gradient step y -= alphaCg p,
  // g -= alphaCg A p on each row as it reaches it, which saves that step its own pass.
  // With threads > 1 the two sweep blocks (rows.sweepBlockEnd()) run at once, to the same bits.
  double precondition(const ContactRows& rows, std::size_t bodyCount, int threads,
                      std::optional<double> alphaCg = std::nullopt);
  // The same contract with z = (A_FF + eps I)^-1 phi (the "cholesky" preconditioner,
  // free_block_inverse.hpp), factored afresh when the free set has changed.
  double preconditionExactly(const ContactRows& rows, std::size_t bodyCount, int threads,
                             std::optional<double> alphaCg);
  double dvAlongRow(std::size_t k) const;
  double frictionTangentPass(ContactRows& rows, std::vector<BodyVelocity>& velocities, double omega);

  // Per-iteration norms of MPRGP: ||g^P||^2, ||beta||^2, phi~.phi, g.p;
  // with the preconditioner also p.A p of the new direction, and whether restricting it to the
  // free set zeroed an entry.
  struct Measures {
    double projected2 = 0.0, chopped2 = 0.0, reducedFree = 0.0, gDotP = 0.0, pAp = 0.0;
    bool restricted = false;
  };
  // What the phases of one solve share: its rows and velocities, team, size and step length, and
  // the conjugate gradient state carried from one iteration to the next.
  struct Iteration {
    ContactRows& rows;
    std::vector<BodyVelocity>& vel;  // the velocities of scratch_.y0
    int threads = 1;
    bool preconditioned = false;               // settings.preconditioner: symmetric Gauss-Seidel in face
    bool projectedCg = false;                  // settings.expansion: the projected CG step first
    double alphaBar = 1.0, invAlphaBar = 1.0;  // Dostal's expansion step length and its inverse
    double bNorm = 0.0;                        // ||b||, the scale of the residual
    // The next measure() first makes p = z - conjugate p (p = phi - conjugate p unpreconditioned);
    // NaN: p is already up to date.
    double conjugate = std::numeric_limits<double>::quiet_NaN();
    bool apReady = false;  // that measure() also made A p, and p.A p = pApReady
    double pApReady = 0.0;
    bool checkDescent = false;  // p was conjugated across a change of the free set

    std::size_t size() const { return static_cast<std::size_t>(rows.rowCount()); }
    std::size_t bodyCount() const { return vel.size(); }
  };
  // The phases of solve(), in the order an iteration meets them.
  Iteration setUp(ContactRows& rows, std::vector<BodyVelocity>& vel, const NscdSettings& settings, int threads);
  int minimise(Iteration& it, double tolerance, int maxIterations, int iterations);
  Measures measure(Iteration& it);
  void proportionalStep(Iteration& it, const Measures& now);
  bool fitsBounds(const Iteration& it, double alpha);
  void conjugateGradientStep(Iteration& it, double alphaCg, double pAp);
  void expansionStep(Iteration& it);
  bool proportioningStep(Iteration& it, const Measures& now);
  void freeGradientToP(Iteration& it);
  void syncVelocities(Iteration& it);

  // MPRGP state per normal unknown and per body (kept to avoid reallocations).
  struct Scratch {
    std::vector<double> scale, y, y0, g, p, ap, step, aStep, z;
    std::vector<BodyVelocity> dv;
    std::vector<core::Vec3> dvLinear;
    std::vector<double> rowSum, partial;
    std::vector<Measures> measures;
  };
  Scratch scratch_;
  // Compact copies of the rows for the two passes of A p, scaled by s: the Jacobian of unknown k
  // (u_k = n.(v_b - v_a) + (l_b x n).w_b - (l_a x n).w_a, times s_k), and per body the velocity
  // change per unit y_k of each of its unknowns, contiguous so the scatter streams.
  struct GatherRow {
    core::Vec3 n, axn, bxn;
    double bias = 0.0;
    int a = 0, b = 0;
  };
  struct BodyEntry {
    core::Vec3 linear, angular;
    int k = 0;
  };
  std::vector<GatherRow> gatherRows_;
  std::vector<BodyEntry> bodyEntries_;
  // The same without angular parts, used when no row has a lever arm across its normal (spheres).
  struct LinearRow {
    core::Vec3 n;
    double bias = 0.0;
    int a = 0, b = 0;
  };
  struct LinearEntry {
    core::Vec3 linear;
    int k = 0;
  };
  // What the preconditioner's sweeps scatter, per unknown in row order: the inverse masses of a
  // and b (the linear velocity change per unit y_k is -invMa s n on a, invMb s n on b) and, unless
  // linearOnly_, s I_a^-1 (l_a x n) and s I_b^-1 (l_b x n) (the angular change on a is minus the
  // first, on b the second).
  struct SweepMass {
    double invMa = 0.0, invMb = 0.0;
  };
  struct SweepAngular {
    core::Vec3 a, b;
  };
  std::vector<SweepMass> sweepMass_;
  std::vector<SweepAngular> sweepAngular_;
  bool linearOnly_ = false;
  ThreadChoice threadChoice_;   // MPRGP's team against one thread, timed
  FreeBlockInverse freeBlock_;  // the "cholesky" preconditioner's factor
  bool exact_ = false;          // this solve preconditions with freeBlock_ (until a factorisation fails)
  SwitchState switch_;
  std::vector<LinearRow> linearRows_;
  std::vector<LinearEntry> linearEntries_;
  std::vector<int> bodyEntryStart_, bodyCursor_;
  double residual_ = 0.0;
  double operatorBound_ = 0.0;
  MprgpSteps steps_;
};

}  // namespace confpack::nscd
