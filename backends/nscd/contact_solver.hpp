#pragma once
// Contact solver of the nscd backend: nonlinear Gauss-Seidel on contact impulses
// (Moreau 1994; Jean 1999 "The non-smooth contact dynamics method", CMAME 177; LMGC90's NLGS).
//
// Unknowns. One impulse per contact point and step (force x dt): r_n >= 0 along the normal n
// (from a to b; +r_n n acts on b, -r_n n on a), plus (r_t1, r_t2) along a fixed tangent basis for
// points on a side wall with friction mu_w > 0. Grain-grain and floor contacts are frictionless.
//
// Kinematics. With lever arms l_a = x_c - x_a, l_b = x_c - x_b' (b' the periodic image of b), the
// relative velocity of b with respect to a at the point, along a unit direction e, is
//     u_e = e.(v_b - v_a) + (l_b x e).w_b - (l_a x e).w_a
// and v_{i+1} = v_free + M^-1 H r changes it linearly in r through the Delassus operator
//     W = H^T M^-1 H,  local block  W_loc = Q^T [ sum_b (1/m_b) I - [l_b]x I_b^-1 [l_b]x ] Q,
// Q = (n, t1, t2) the contact frame, I_b^-1 the world-frame inverse inertia R I_body^-1 R^T.
// For a frictionless row  W_nn = sum_b ( 1/m_b + (l_b x n).I_b^-1 (l_b x n) ).
//
// Contact law (velocity Signorini with e_n = 0 and a gap term; g_m = gap in q_m):
//     u_n + c >= 0,  r_n >= 0,  r_n (u_n + c) = 0,
//     c = g_m / dt                                   if g_m >= 0,
//     c = max(beta g_m / dt, -v_corr)                 if g_m < 0 (overlap).
// Why g_m / dt and not g_m / (theta dt): the next step's predicted gap is, to first order,
// g_m' = g_m + theta dt u + (1 - theta) dt u = g_m + dt u. Asking u >= -g_m/dt therefore lets a grain
// close an open gap exactly within one step (no artificial gaps, no bounce: e_n = 0) and leaves
// g_m' >= 0, so no overlap is created. With g_m / (theta dt) the end-of-step gap closes but, for
// theta < 1, the next predicted gap is negative and the velocity flips sign every step (a
// period-2 oscillation that never decays at theta = 1/2). Overlaps (only from unconverged
// sweeps or the curvature of rotations) are removed by a fraction beta per step, capped at v_corr.
//
// Side-wall friction (Coulomb, e_t = 0): ||r_t|| <= mu r_n; u_t = 0 if ||r_t|| < mu r_n, otherwise
// r_t = -mu r_n u_t / ||u_t||.
//
// Gauss-Seidel update of one row (a few dozen flops, Jacobian pieces precomputed):
//     r_n <- max(0, r_n - omega (u_n + c) / W_nn)      (omega = 1: plain Gauss-Seidel; option)
// and for a friction point, after its normal update, in the same visit,
//     r_t <- proj_{||r_t|| <= mu r_n} ( r_t - u_t / w_t ),   w_t = largest eigenvalue of W_tt.
// A scalar w_t (not W_tt^-1) keeps the fixed point exactly Coulomb's law: on the disc boundary,
// u_t = -(lambda - 1) w_t r_t is anti-parallel to r_t; inside, u_t = 0.
// Multi-point contacts (double, triple) are solved point by point as independent rows sharing the
// normal: the total force and moment of the contact converge, while their split between points is
// whatever the sweep reaches (the static problem leaves it undetermined).
//
// Convergence ("Quad"-type relative norm over one sweep k):
//     eps_k = sqrt( sum_rows ||r^k - r^(k-1)||^2 / sum_rows ||r^k||^2 ),
// stop when eps_k < tolerance (after min_iterations) or after max_iterations sweeps.
// Sweep order: frictionless rows sorted by the height z of their contact point, lowest first (ties by
// bodies a, b, then contact and point index), then the side-wall friction rows in contact order.
// The order depends only on the configuration: bitwise determinism. Measured on a 536-sphere pile
// near jamming (one cold static solve to eps < 1e-6): bottom-to-top needs 4260 / 1390 / 1310 sweeps
// at omega = 1.5 / 1.8 / 1.85 against 4470 / 2030 / 1400 in contact order; top-to-bottom is no
// better than contact order (a velocity-level sweep does not carry weight down a chain in one pass:
// the top contact of a free-falling column sees zero relative velocity).
// The stopping rule stays the impulse norm above: a rule on the largest velocity error per row
// (|u_n + c| below 3e-4 g dt) stopped earlier (1270 versus 1900 sweeps per step) but left
// max |sum F| / (d^2 P) at 1e-3 to 3e-3 instead of 2e-4 to 1.5e-3 (both at omega = 1.85, same pile
// restarted at rest, t + 8 to t + 27): near jamming W is ill-conditioned,
// so a small H^T dv does not bound the impulse (force) error.
//
// Two solvers of the same problem (NscdSettings::solver).
// - "nlgs", the Gauss-Seidel above (SPEC 5.1, LMGC90's NLGS). Cheap per sweep and robust, but its
//   error near jamming shrinks by a factor close to 1 per sweep (the Delassus matrix of a jammed,
//   nearly isostatic pile is ill-conditioned): it stops on a small change per sweep while the
//   impulses are still far from the solution, and that error is a force imbalance on every grain.
// - "mprgp" (default; contact_solver_mprgp.cpp): the frictionless part is the convex quadratic
//   program  min 1/2 r.W r + r.(u_free + c)  over r >= 0, whose optimality conditions are exactly
//   the Signorini law above; it is solved by Dostal's MPRGP, conjugate gradients with gradient
//   projections for the bounds (after LMGC90's conjugate-gradient solvers, Renouf & Alart 2004).
//   Iterations grow like the square root of the condition number instead of linearly, and the
//   stopping rule is the true residual of the law. Its conjugate gradients are preconditioned on
//   the free set by a forward and a backward Gauss-Seidel sweep (NscdSettings::preconditioner):
//   the sweeps of nlgs serve inside MPRGP, where they cut the iterations 2.5 to 3.5 times.
//   A sweep is serial by nature; for two threads the rows are ordered in blocks (prepare()): on a
//   box with L_x >= 16 lever arms, first the rows of the two halves of the box along x, less the
//   strips within a lever arm of their edges, each half bottom to top, then the strip rows bottom
//   to top. The halves share no grain, so two threads sweep them at once and give the bits of
//   one: the order depends on the configuration only, never on the thread count. On one thread
//   it costs a few iterations: 58.5 against 57.7 per step on 8,000 spheres between walls (first
//   6 t0), 69.9 against 66.7 on 2,000 in a biperiodic 10.4 x 10.4 box (first 8 t0), where the
//   strips hold a fifth of the rows. Two threads ran the 8,000-sphere case 1.33x faster.
//   The passes around the solve (building the rows, sorting their keys, the warm start's lookups,
//   MPRGP's scatter entries and operator bound, the export to the cache) were also tried on the
//   team, each part writing only its own rows, and not kept: on this 2-core machine they were no
//   faster (prepare 2.58 s on two threads against 2.18 s on one, one run each; 8,000 spheres
//   between walls, first 3.5 t0): they stream memory, and this machine's bandwidth grows only
//   1.4x with the second core (one streaming loop 10.5 GB/s, one on each core 15.1 GB/s).
//   Wall friction (Coulomb, not a quadratic program) is handled by block Gauss-Seidel: MPRGP on
//   every normal impulse with the tangential ones fixed, then one projected pass over the
//   tangential impulses, until both have converged.
//   Measured on the same 493-sphere biperiodic pile (seed 1): with nlgs at its default tolerance
//   1e-6, the largest |sum F| / (d^2 P) stays at 2.5e-3 after 40 t0 and ~1,000 sweeps per step;
//   with mprgp at 1e-10, SPEC 6.1 holds from t = 39.8 with ~400 iterations per step.
#include <array>
#include <optional>
#include <utility>
#include <vector>

#include "backends/nscd/contact_cache.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "backends/nscd/thread_choice.hpp"

namespace confpack::nscd {

/// Linear and angular velocity of a body (hot solver state, apart from mass properties).
struct BodyVelocity {
  core::Vec3 v = core::Vec3::Zero();
  core::Vec3 w = core::Vec3::Zero();
};

/// Inverse mass properties in the current configuration (world frame).
struct BodyInverseMass {
  double invMass = 0.0;
  core::Mat3 invInertia = core::Mat3::Zero();
};

class ContactSolver {
 public:
  /// Builds the rows of every contact point: lever arms from `positions` (q_m), Delassus diagonal,
  /// gap-correction bias. `bodies` has one entry per grain plus a last, static one (zero inverse
  /// mass) standing for the walls. `wallFriction` is mu_w (applies to side walls only).
  void prepare(const std::vector<ContactGeometry>& contacts, const std::vector<core::Vec3>& positions,
               const std::vector<BodyInverseMass>& bodies, const core::BoxDef& box, double dt,
               const NscdSettings& settings);
  /// Sets the impulses from the cache (scaled to this dt) and applies them to the velocities;
  /// with mprgp (the solver of the last prepare()), only the tangential ones: solve() applies the
  /// normal impulses in its own pass over the bodies.
  void warmStart(const ContactCache& cache, const std::vector<ContactGeometry>& contacts, double dt,
                 std::vector<BodyVelocity>& velocities);
  /// Solves the step's contact problem with settings.solver, updating `velocities` (v_free plus
  /// the warm start on entry, v_{i+1} on exit); returns the number of iterations: Gauss-Seidel
  /// sweeps (nlgs) or operator applications W p (mprgp, each about two sweeps of work).
  int solve(std::vector<BodyVelocity>& velocities, const NscdSettings& settings);
  double residual() const { return residual_; }
  /// The grains touched by the rows of each of the two sweep blocks of the last prepare(), sorted,
  /// without `world` (the static body); both empty when the rows are not split. The blocks are
  /// swept at once by two threads, so they must share none.
  std::array<std::vector<int>, 2> sweepBlockBodies(int world) const;
  /// What the MPRGP iterations of the last solve were (their sum is its iteration count, less the
  /// tangential passes with wall friction).
  struct MprgpSteps {
    int conjugate = 0;      ///< conjugate gradient steps
    int projected = 0;      ///< expansions by a projected conjugate gradient step
    int gradient = 0;       ///< expansions by Dostal's step (first bound, then projected gradient)
    int proportioning = 0;  ///< proportioning steps (release of bound unknowns)
  };
  const MprgpSteps& mprgpSteps() const { return steps_; }
  /// The upper bound of ||S W S|| (S = diag(W_kk^-1/2)) that set the expansion step of the last
  /// MPRGP solve (alpha_bar = 1.95 / bound); 0 before any.
  double operatorBound() const { return operatorBound_; }
  int rowCount() const { return static_cast<int>(normalRows_.size() + frictionRows_.size()); }

  /// Impulses of contact c, point p, after solve(): normal and tangential (world vector).
  double normalImpulse(int c, int p) const;
  core::Vec3 tangentImpulse(int c, int p) const;
  /// Writes the solution into cache entries (same order as the contacts).
  void exportImpulses(const std::vector<ContactGeometry>& contacts, std::vector<CachedContact>& out) const;

 private:
  struct NormalRow {
    core::Vec3 n, axn, bxn, iaAxn, ibBxn;  // Jacobian pieces: n, l_a x n, l_b x n, I_a^-1 (l_a x n), ...
    double invMa = 0.0, invMb = 0.0;
    double invW = 0.0;   // 1 / W_nn
    double bias = 0.0;   // c of the contact law [d_L / t0]
    double r = 0.0;      // impulse
    int a = 0, b = 0;    // body indices (b = the static body for walls)
    double z = 0.0;      // height of the contact point
    double x = 0.0;      // its abscissa (the sweep's blocks)
    int segment = 0;     // sweep block (see prepare)
    int c = 0, p = 0;    // contact and point index (sort ties)
  };
  int solveNlgs(std::vector<BodyVelocity>& velocities, const NscdSettings& settings);
  int solveMprgp(std::vector<BodyVelocity>& velocities, const NscdSettings& settings);
  // MPRGP building blocks (contact_solver_mprgp.cpp) over the normal unknowns (frictionless rows,
  // then the normal part of the friction rows), in the scaled variables y = r / s (s = W_nn^-1/2).
  void buildMprgpRows(std::size_t bodyCount);
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
  // z = M_F^-1 g on the free set F = {y > 0} (0 elsewhere), M_F the symmetric Gauss-Seidel
  // splitting of A restricted to F, leaving M^-1 H S z in dvLinear_ / dv_; returns z . ap_.
  // Given alphaCg, the forward sweep first makes the conjugate gradient step y -= alphaCg p,
  // g -= alphaCg A p on each row as it reaches it, which saves that step its own pass.
  // With threads > 1 the two sweep blocks (sweepBlockEnd_) run at once, to the same bits.
  double precondition(std::size_t bodyCount, int threads, std::optional<double> alphaCg = std::nullopt);
  double dvAlongRow(std::size_t k) const;
  double frictionTangentPass(std::vector<BodyVelocity>& velocities);
  struct FrictionRow;
  static std::pair<double, double> updateTangent(FrictionRow& row, BodyVelocity& va);

  struct FrictionRow {   // a point on a side wall: b is static
    core::Vec3 n, t1, t2, axn, axt1, axt2, iaAxn, iaAxt1, iaAxt2;
    double invMa = 0.0, invWnn = 0.0, invWt = 0.0, bias = 0.0, mu = 0.0;
    double rn = 0.0, rt1 = 0.0, rt2 = 0.0;
    int a = 0;
  };
  // Where the rows of contact c start: rowRef_[c] = {is friction, first row index}.
  struct RowRef {
    bool friction = false;
    int first = 0;
  };
  std::vector<NormalRow> normalRows_;
  std::vector<FrictionRow> frictionRows_;
  std::vector<RowRef> rowRef_;
  // Normal rows are stored in sweep order; the row of contact c, point p (frictionless) is
  // normalRows_[slot_[rowRef_[c].first + p]].
  std::vector<int> slot_;
  // The normal impulse of each frictionless row in contact order (row ref.first + p of contact c),
  // set by solve().
  std::vector<double> impulseOfRow_;
  // Sweep blocks of the normal rows (prepare()): [0, e0) and [e0, e1) share no grain; [e1, m) is
  // swept serially. e0 = e1 = 0 when the box is not split.
  int sweepBlockEnd_[2] = {0, 0};
  std::vector<NormalRow> sorted_;  // scratch of prepare(), kept to avoid reallocations
  struct SortKey {  // a row's place in the sweep order (prepare())
    int segment;
    double z;
    int a, b, c, p;
    int index;
  };
  std::vector<SortKey> sortKeys_;
  // MPRGP state per normal unknown and per body (kept to avoid reallocations).
  std::vector<double> scale_, y_, y0_, g_, p_, ap_, step_, aStep_, z_;
  std::vector<BodyVelocity> dv_;
  std::vector<core::Vec3> dvLinear_;
  std::vector<double> rowSum_, partial_;
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
  // The warm start's normal impulses are applied to the velocities by solveMprgp(), one pass per
  // body over its scatter entries, on the solver's team, instead of by warmStart(), contact by
  // contact through the rows in sweep order (a cache miss per point).
  bool warmNormalsInSolve_ = false;
  ThreadChoice threadChoice_;  // MPRGP's team against one thread, timed
  std::vector<LinearRow> linearRows_;
  std::vector<LinearEntry> linearEntries_;
  std::vector<int> bodyEntryStart_, bodyCursor_;
  // Per-iteration norms of MPRGP: ||g^P||^2, ||beta||^2, phi~.phi, g.p;
  // with the preconditioner also p.A p of the new direction, and whether restricting it to the
  // free set zeroed an entry.
  struct Measures {
    double projected2 = 0.0, chopped2 = 0.0, reducedFree = 0.0, gDotP = 0.0, pAp = 0.0;
    bool restricted = false;
  };
  std::vector<Measures> measures_;
  double residual_ = 0.0;
  double operatorBound_ = 0.0;
  MprgpSteps steps_;
};

}  // namespace confpack::nscd
