#pragma once
// Settings of the native contact dynamics backend (docs/model.md, "nscd: Moreau-Jean contact
// dynamics"), with their JSON round trip.
// Every key of the options JSON is a field below; unknown keys are refused so that a typo never
// silently runs with a default. The measurements behind the defaults are in docs/performance.md,
// "nscd settings: the measurements behind the defaults".
#include <nlohmann/json.hpp>
#include <string>

#include "core/settings_table.hpp"

namespace confpack::nscd {

/// Algorithm that solves the contact problem of one step (the contact law is the same).
enum class SolverKind {
  Nlgs,   ///< "nlgs": nonlinear (projected) Gauss-Seidel over contact points (LMGC90's NLGS)
  Mprgp,  ///< "mprgp": projected conjugate gradient (Dostal's MPRGP) on the same problem
  Ipm,    ///< "ipm": primal-dual interior point with a sparse Cholesky factorisation (ipm_solver.hpp)
};

/// The solver of the quasi-static finisher's steps.
enum class FinisherSolverKind {
  Auto,   ///< "auto": ipm when every grain is a sphere, mprgp otherwise (the measurements: below)
  Ipm,    ///< "ipm": the interior-point method (ipm_solver.hpp)
  Mprgp,  ///< "mprgp": MPRGP, as the dynamic steps
};

/// How MPRGP expands the active set when a conjugate gradient step would leave y >= 0.
enum class ExpansionKind {
  ProjectedCg,  ///< "projected_cg": the whole CG step projected on y >= 0, if it lowers the energy
  Gradient,     ///< "gradient": Dostal's step to the first bound, then a fixed projected gradient step
};

/// Preconditioner of MPRGP's conjugate gradients on the free set ("in face", Dostal 2009).
enum class PreconditionerKind {
  SymmetricGaussSeidel,  ///< "sgs": one forward and one backward Gauss-Seidel sweep over the free rows
  None,                  ///< "none": Jacobi scaling only (A has a unit diagonal)
  Cholesky,              ///< "cholesky": (A_FF + eps I)^-1 exactly, by a sparse Cholesky factorisation in body space
  Switching,             ///< "switching": "sgs" until a solve is dear, then "cholesky" (NscdSettings::preconditioner)
};

/// What the contact law does with an overlap (docs/model.md, "The paper-like contact model").
enum class ContactLaw {
  Gap,       ///< "gap": u_n + c >= 0 with c = g / dt for a gap, beta g / dt (capped) for an overlap
  Velocity,  ///< "velocity": u_n + max(0, g / dt) >= 0: an overlap is held, never corrected
};

/// How the points and gaps of a polyhedron contact are found.
enum class ContactDetection {
  Exact,        ///< "exact": every point its own exact gap (collision/contact_region.hpp)
  CommonPlane,  ///< "common_plane": the vertices within a band of the common plane, one gap for all
};

/// Options of the nscd backend. JSON keys in brackets.
struct NscdSettings {
  /// ["theta"] Moreau-Jean theta in [0.5, 1] [-]. 0.5 integrates constant forces exactly
  /// (free fall has zero position error); 1 is the fully implicit (dissipative) scheme.
  double theta = 0.5;
  /// ["solver"] "mprgp" (default) or "nlgs"; contact_solver.hpp states both and why the default
  /// is not Gauss-Seidel: near jamming Gauss-Seidel cannot converge far enough, in practical
  /// time, for the equilibrium test's force balance.
  SolverKind solver = SolverKind::Mprgp;
  /// ["tolerance"] stopping threshold of the solver [-], > 0; its default depends on the solver.
  /// nlgs: relative impulse change of one sweep, eps = sqrt(sum_rows |r^k - r^(k-1)|^2 /
  /// sum_rows |r^k|^2) (a "Quad"-type norm: every row counts with its impulse vector, normal and
  /// tangential); default 1e-6 (at 1e-4 a pile's force ratio never gets below about 1e-2).
  /// mprgp: relative projected gradient ||g^P|| / ||b||, the contact velocity residual of the
  /// Signorini law over that of zero impulses (mprgp_solver.cpp); default 1e-10 (at 1e-8 a pile
  /// at rest keeps a force ratio near 2e-4, above the equilibrium bound 1e-4; 1e-9 got there
  /// later overall).
  double tolerance = 1e-10;
  /// ["finisher_solver"] the solver of the quasi-static finisher's steps (docs/model.md,
  /// "Quasi-static compaction"): "auto" (default), "ipm" or "mprgp" ("nlgs" is refused: it cannot
  /// reach the finisher's accuracy). Its iteration cap is max_iterations when it is also `solver`,
  /// else its own default; its tolerance is `tolerance` (the same relative projected gradient for
  /// mprgp and ipm), or 1e-10 under nlgs.
  /// "auto" takes ipm for sphere piles, where its finisher was 0.85 to 0.52 times MPRGP's time,
  /// and mprgp for pinacoid piles until one of its solves ends at the iteration cap, ipm from the
  /// next step on: MPRGP is the cheaper on small pinacoid piles, and on a 1,064-pinacoid pile it
  /// ended every step at its cap, inexact, and the finisher never settled (docs/performance.md,
  /// "The interior-point finisher" and "The finisher's solves at their cap"). Between frictional
  /// walls pinacoid piles keep mprgp: there the interior point's steps were the worse
  /// (docs/limitations.md).
  FinisherSolverKind finisherSolver = FinisherSolverKind::Auto;
  /// ["expansion"] (mprgp) "projected_cg" (default) or "gradient": the step taken when a
  /// conjugate gradient step would make an impulse negative (mprgp_solver.cpp).
  /// "gradient" is Dostal's original: to the first bound, then a projected gradient step of fixed
  /// length 1.95 / ||A||, and conjugate gradients restart. In a loading pile nearly every second
  /// step was one, so conjugate gradients hardly ever ran two steps in a row. "projected_cg" takes
  /// the whole conjugate gradient step projected on r >= 0 when that lowers the energy, else
  /// Dostal's step (after Kruzik et al. 2020), and goes on conjugating from it instead of
  /// restarting. It saves most while contacts open and close and nothing near jamming
  /// (mprgp_solver.cpp).
  ExpansionKind expansion = ExpansionKind::ProjectedCg;
  /// ["preconditioner"] (mprgp) "sgs" (default) or "none": how conjugate gradients are
  /// preconditioned on the free set (mprgp_solver.cpp). "sgs" applies one forward and one
  /// backward Gauss-Seidel sweep over the free rows per iteration, which about doubles the cost of
  /// an iteration and cuts the iterations 2.5 to 3.5 times: a step's solve takes about a third
  /// less time (docs/performance.md, "The preconditioner and the creep's solve").
  /// "cholesky" applies (A_FF + eps I)^-1 exactly through a sparse Cholesky factorisation of the
  /// body-space matrix eps M + G_F^T G_F (free_block_inverse.hpp), refactored when the free set
  /// changes: 6 to 12 iterations where "sgs" needs hundreds near jamming, for a factorisation
  /// or more per step (docs/performance.md, "The preconditioner and the creep's solve").
  /// "switching" starts with "sgs" and hands a solve to "cholesky" once it has taken
  /// preconditioner_switch x (its rows) iterations without converging; the next solves then start
  /// with "cholesky", and every kSwitchProbeInterval-th of them tries "sgs" again, kept if it converges
  /// within that budget. A deterministic rule (iteration counts, not timings), so a run repeats to
  /// the bit: it takes "cholesky" for the last stretch to rest, where "sgs" needs thousands of
  /// iterations a step; msp-w10 came to rest 1.5 times faster, but the medium study's r0008 crept
  /// on to its fall's limit and took 2.8 times longer, so "sgs" stays the default
  /// (docs/performance.md, "The preconditioner and the creep's solve").
  PreconditionerKind preconditioner = PreconditionerKind::SymmetricGaussSeidel;
  /// ["preconditioner_switch"] (mprgp, "switching") iterations a solve may take with "sgs", per
  /// normal row, before it goes on with "cholesky" [-], > 0. 0.2: a "cholesky" step cost about as
  /// much as 0.2 x rows "sgs" iterations on r0008 and msp-w10 (the same page).
  double preconditionerSwitch = 0.2;
  /// ["preconditioner_shift"] (mprgp, "cholesky" and "switching") eps > 0 [-, A has a unit diagonal]. 1e-5: the
  /// creep blocks' softest eigenvalues are ~1e-4, so all but a few become ~1 (6 iterations to 1e-10
  /// on a 1,648-sphere block against 12 at 1e-4), and eps M keeps K positive definite where grains
  /// have fewer than 3 contacts; K's conditioning (~||A|| / eps) still leaves z ten digits.
  double preconditionerShift = 1e-5;
  /// ["max_iterations"] cap on the iterations per step [-], >= 1: sweeps (nlgs, default 2000) or
  /// applications of W (mprgp, default 5000; the jammed 493-sphere pile needs ~400 at 1e-10).
  int maxIterations = 5000;
  /// ["min_iterations"] (nlgs) sweeps done even when the first ones already look converged [-], >= 1.
  int minIterations = 2;
  /// ["relaxation"] (nlgs) over-relaxation factor omega in (0, 2) of the projected Gauss-Seidel update
  /// r <- proj(r - omega (u + c) / W) [-]. 1 is plain Gauss-Seidel; projected SOR converges for
  /// any omega in (0, 2) on the frictionless (symmetric) problem, friction rows use omega = 1.
  /// Default 1.5: it needs 2.6 times fewer sweeps than 1 on a compacting pile, while an
  /// isolated contact's error still shrinks fast (by |1 - omega| per sweep); at 1.85, better for
  /// a large pile near jamming, the resting-force conformance tests miss their 1e-8 bounds.
  double relaxation = 1.5;
  /// ["friction_relaxation"] (mprgp) over-relaxation factor omega_t in (0, 2) of the tangential
  /// passes around side-wall friction, r_t <- proj_disc(r_t - omega_t u_t / W_tt) [-]. Each normal
  /// solve is followed by one such pass until both have converged (mprgp_solver.hpp), to the
  /// same tolerance whatever omega_t. Default 1.2: 1.17 times less time than 1 on 18 medium
  /// piles between frictional walls, and no value from 1.1 to 1.5 better on both mu_w = 0.5
  /// and 1 (docs/performance.md, "Over-relaxed friction passes").
  double frictionRelaxation = 1.2;
  /// ["alert_distance"] a pair becomes a contact row when its gap in the predicted configuration
  /// is below alert_distance x (the smaller size of the pair, or the grain size for a wall)
  /// [fraction of d]. Must exceed the largest approach per step (d/100, docs/model.md, "Time
  /// step"). >= 0.
  double alertDistance = 0.03;
  /// ["gap_correction"] fraction beta in (0, 1] of an overlap removed per step. The contact law
  /// imposes u_n >= -g_m / dt for an open gap g_m >= 0 (grains may close the gap exactly, with no
  /// bounce) and u_n >= -beta g_m / dt for an overlap g_m < 0 (a bounded separation velocity that
  /// removes the overlap geometrically, without kicking grains out of the pile). [-]
  double gapCorrection = 0.2;
  /// ["max_correction_velocity"] upper bound of the separation velocity the overlap correction
  /// may ask for [sqrt(g d_L)], > 0. Protects against an initial configuration with large
  /// overlaps exploding; irrelevant once the overlaps are small.
  double maxCorrectionVelocity = 0.05;
  /// ["contact_law"] "gap" (default) or "velocity". "gap" is the law above. "velocity" is the
  /// law of LMGC90's rigid-rigid IQS laws: u_n + max(0, g_m / dt) >= 0, so that an open gap
  /// closes exactly as under "gap" while an overlap, once made (an unconverged solve, a step's
  /// overshoot), is held and never pushed back out; gap_correction and max_correction_velocity
  /// are then unused, also in the quasi-static finisher. Default "gap": the exact model, whose
  /// piles do not interpenetrate.
  ContactLaw contactLaw = ContactLaw::Gap;
  /// ["contact_detection"] "exact" (default) or "common_plane": the points of a polyhedron pair
  /// and their gaps. "exact" gives each point its own gap (collision/contact_region.hpp).
  /// "common_plane" reads a pair as LMGC90's common-plane detection does
  /// (collision::collideCommonPlane): at least 3 vertices of each grain within the band of the
  /// mid plane make a face-to-face contact whose points, at most 4 corners of the overlap of the
  /// two vertex sets' projections, all get the pair's one gap; an empty overlap is no contact.
  /// Other pairs, sphere contacts and wall contacts are read exactly under both.
  ContactDetection contactDetection = ContactDetection::Exact;
  /// ["common_plane_band"] (common_plane) half-width of the band about the mid plane within which
  /// a vertex counts as touching, max(0, g / 2) + band x ref, ref the smaller distance from a
  /// grain's centre to its extreme vertex along the normal (about half a grain size) [-], > 0.
  /// Default 0.1: LMGC90's default (its "cundall_neighbor").
  double commonPlaneBand = 0.1;
  /// ["damping"] viscous damping rate c >= 0 of slow grains in contact [sqrt(g / d_L)]: each step
  /// the velocity and angular velocity of every grain that carried a contact impulse in the last
  /// step and moves slower than damping_speed are multiplied by exp(-c dt). Grains in free flight
  /// are not damped and a static packing is not moved (its velocities are zero), so the
  /// equilibria it reaches are equilibria of the undamped model. Default 0: the contact law alone
  /// (e_n = 0) dissipates only when contacts close or slide on a wall, and a frictionless
  /// pinacoid pile can keep a grain swinging on contacts that never open, which the equilibrium
  /// test then never accepts (docs/limitations.md).
  double damping = 0.0;
  /// ["damping_speed"] grains faster than this are not damped [sqrt(g d_L)], > 0, or null for no
  /// limit. Default 0.01: it keeps the damping off the flow that forms the packing, which
  /// damping every loaded grain loosens (phi 0.627 against 0.641 undamped on a sphere pile).
  double dampingSpeed = 0.01;
  /// ["fall_tolerance"] stopping threshold of the solves of the quasi-static protocol's fall
  /// (ContactBackend::startQuasiStaticFall), in `tolerance`'s measure, > 0, or "auto" (0 here):
  /// 1e-6 for a pile with pinacoids, `tolerance` for a sphere pile. The finisher balances the
  /// fall's last state with its own solves, so the fall need not be balanced to 1e-10: pinacoid
  /// falls take about 6 times fewer iterations so, while a sphere pile crept longer for the same
  /// iterations (docs/performance.md, "The fall solved to 1e-6").
  double fallTolerance = 0.0;
  /// Throws std::invalid_argument naming the field if a value is out of range.
  void validate() const;
};

/// "switching": every this many solves started with "cholesky", one starts with "sgs" again [-].
inline constexpr int kSwitchProbeInterval = 16;

/// fall_tolerance's "auto" for pinacoid piles [-].
inline constexpr double kPinacoidFallTolerance = 1e-6;

/// The keys of NscdSettings with their units, ranges and meaning (core/settings_table.hpp): the
/// JSON reader and writer, validate() and the docs' table all come from it.
const core::SettingsTable<NscdSettings>& settingsTable();
void to_json(nlohmann::json& j, const NscdSettings& s);
/// Defaults of the solver-dependent settings (tolerance, max_iterations) for `kind`.
NscdSettings defaultsFor(SolverKind kind);
/// Reads the keys that are present (missing ones keep their defaults); throws
/// std::invalid_argument for an unknown key, a value of the wrong type, or one out of range.
NscdSettings settingsFromJson(const nlohmann::json& j);

}  // namespace confpack::nscd
