#pragma once
// Settings of the native contact dynamics backend (SPEC 5.1), with their JSON round trip.
// Every key of the options JSON is a field below; unknown keys are refused so that a typo never
// silently runs with a default.
#include <nlohmann/json.hpp>
#include <string>

namespace confpack::nscd {

/// Algorithm that solves the contact problem of one step (the contact law is the same).
enum class SolverKind {
  Nlgs,   ///< "nlgs": nonlinear (projected) Gauss-Seidel over contact points, SPEC 5.1
  Mprgp,  ///< "mprgp": projected conjugate gradient (Dostal's MPRGP) on the same problem
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
};

/// Options of the nscd backend. JSON keys in brackets.
struct NscdSettings {
  /// ["theta"] Moreau-Jean theta in [0.5, 1] [-]. 0.5 integrates constant forces exactly
  /// (free fall has zero position error); 1 is the fully implicit (dissipative) scheme.
  double theta = 0.5;
  /// ["solver"] "mprgp" (default) or "nlgs"; contact_solver.hpp states both and why the default
  /// is not SPEC 5.1's Gauss-Seidel: near jamming Gauss-Seidel cannot converge far enough, in
  /// practical time, for the SPEC 6.1 force balance.
  SolverKind solver = SolverKind::Mprgp;
  /// ["tolerance"] stopping threshold of the solver [-], > 0; its default depends on the solver.
  /// nlgs: relative impulse change of one sweep, eps = sqrt(sum_rows |r^k - r^(k-1)|^2 /
  /// sum_rows |r^k|^2) (a "Quad"-type norm: every row counts with its impulse vector, normal and
  /// tangential); default 1e-6 (at 1e-4 a 536-sphere pile never gets below |sum F| ~ 1e-2 d^2 P).
  /// mprgp: relative projected gradient ||g^P|| / ||b||, the contact velocity residual of the
  /// Signorini law over that of zero impulses (mprgp_solver.cpp); default 1e-10. Measured
  /// on a 493-sphere pile: the largest |sum F| / (d^2 P) settles near 7e-3 at 1e-6 (run from the
  /// deposit to t = 60), and, restarted at rest from t = 30 for 3000 steps, near 2e-4 at 1e-8
  /// (above the SPEC 6.1 bound 1e-4) and at 1e-6 to 4e-6 at 1e-10. A looser 1e-9 is not faster
  /// overall: from the deposit, the same pile met SPEC 6.1 after 27,600 steps at 365 iterations
  /// per step (231 s), against 16,600 steps at 419 (151 s) with 1e-10, the two run side by side.
  double tolerance = 1e-10;
  /// ["expansion"] (mprgp) "projected_cg" (default) or "gradient": the step taken when a
  /// conjugate gradient step would make an impulse negative (mprgp_solver.cpp).
  /// "gradient" is Dostal's original: to the first bound, then a projected gradient step of fixed
  /// length 1.95 / ||A||, and conjugate gradients restart. In a loading pile nearly every second
  /// step was one (2,000 spheres, 4 t0 fall and 200 steps: 162k conjugate gradient steps, 139k
  /// expansions), so conjugate gradients hardly ever ran two steps in a row. "projected_cg" takes
  /// the whole conjugate gradient step projected on r >= 0 when that lowers the energy, else
  /// Dostal's step (after Kruzik et al. 2020), and goes on conjugating from it instead of
  /// restarting. It saves most while contacts open and close (22% of the solve time on that
  /// pile) and nothing near jamming; measurements in mprgp_solver.cpp and docs/performance.md.
  ExpansionKind expansion = ExpansionKind::ProjectedCg;
  /// ["preconditioner"] (mprgp) "sgs" (default) or "none": how conjugate gradients are
  /// preconditioned on the free set (mprgp_solver.cpp). "sgs" applies one forward and one
  /// backward Gauss-Seidel sweep over the free rows per iteration, which about doubles the cost of
  /// an iteration and cuts the iterations 2.5 to 3.5 times. Measured, the two side by side on the
  /// 493-sphere biperiodic pile (6 x 6, h = 12), seeds 1 to 10, up to 60 t0: 139 to 179 iterations
  /// and 4.2 to 5.2 ms of solve per step with "sgs", 429 to 559 and 7.5 to 9.6 ms with "none";
  /// 2,000 spheres over their first 8 t0, 67 against 173 iterations per step, solve time x0.65;
  /// 188 pinacoids over 6 t0, 16 against 34, x0.66. The time to equilibrium follows the trajectory,
  /// not only the cost per step: within 60 t0, over seeds 1 to 20, "none" reached it 14 times and
  /// "sgs" 12; seed by seed "none" got there first 11 times and "sgs" 7 (sign test p ~ 0.5: no
  /// effect shown), with median wall times of 159 and 113 s (docs/performance.md).
  PreconditionerKind preconditioner = PreconditionerKind::SymmetricGaussSeidel;
  /// ["max_iterations"] cap on the iterations per step [-], >= 1: sweeps (nlgs, default 2000) or
  /// applications of W (mprgp, default 5000; the jammed 493-sphere pile needs ~400 at 1e-10).
  int maxIterations = 5000;
  /// ["min_iterations"] (nlgs) sweeps done even when the first ones already look converged [-], >= 1.
  int minIterations = 2;
  /// ["relaxation"] (nlgs) over-relaxation factor omega in (0, 2) of the projected Gauss-Seidel update
  /// r <- proj(r - omega (u + c) / W) [-]. 1 is plain Gauss-Seidel; projected SOR converges for
  /// any omega in (0, 2) on the frictionless (symmetric) problem, friction rows use omega = 1.
  /// Default 1.5: on a 536-sphere pile compacting under gravity at tolerance 1e-6 it needed 2.6x
  /// fewer sweeps than plain Gauss-Seidel over the first 10 t0 (223 versus 587 per step). With 1,
  /// an isolated contact is solved exactly in one sweep; otherwise to within the tolerance (its
  /// error shrinks by |1 - omega| per sweep, which is why the default is not higher: at 1.85 the
  /// resting-force conformance tests miss their 1e-8 bounds and a cached column needs 8 sweeps).
  /// For a large pile near jamming, 1.85 is better (measured on that pile restarted at rest from
  /// t = 50 with cap 2000: 1.5 sits at the cap, ~1990 sweeps per step, max |sum F| / (d^2 P) 4e-4
  /// to 1e-1 over the next 10 t0; 1.85 takes ~1200 sweeps over the first 3 t0 and ~1900 later,
  /// force ratio 2e-4 to 1.5e-3 with SPEC 6.1 met at some steps from t + 10.5; from the deposit,
  /// first 8 t0: 152 versus 178 sweeps per step). One cold static solve of that pile to 1e-6:
  /// 4260 sweeps at 1.5, 1310 at 1.85, 1450 at 1.9, 2300 at 1.95.
  double relaxation = 1.5;
  /// ["alert_distance"] a pair becomes a contact row when its gap in the predicted configuration
  /// is below alert_distance x (the smaller size of the pair, or the grain size for a wall)
  /// [fraction of d]. Must exceed the largest approach per step (SPEC 4: d/100). >= 0.
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
  /// ["damping"] viscous damping rate c >= 0 of slow grains in contact [sqrt(g / d_L)]: each step
  /// the velocity and angular velocity of every grain that carried a contact impulse in the last
  /// step and moves slower than damping_speed are multiplied by exp(-c dt). Grains in free flight
  /// are not damped and a static packing is not moved (its velocities are zero), so SPEC 6.1
  /// equilibria are equilibria of the undamped model. Default 0: the contact law alone (e_n = 0)
  /// dissipates only when contacts close or slide on a wall. A frictionless pinacoid pile can keep
  /// a grain oscillating on contacts that never open (measured on 188 pinacoids: period 3.6 t0,
  /// |v| ~ 2e-3 sqrt(g d), undamped over 10 t0), which SPEC 6.1 then never accepts; restarted at
  /// 60 t0 with c = 0.4 (no speed limit), that pile met SPEC 6.1 7.4 t0 later at the usual ~690
  /// iterations per step.
  double damping = 0.0;
  /// ["damping_speed"] grains faster than this are not damped [sqrt(g d_L)], > 0, or null for no
  /// limit. Default 0.01: it keeps the damping off the flow that forms the packing. On the
  /// 493-sphere biperiodic pile (6 x 6, h = 12, seed 1) c = 0.4 for every loaded grain gave
  /// phi = 0.627 after 26,200 steps, c = 0.4 below 0.01 gave phi = 0.640 after 18,600 steps, and no
  /// damping phi = 0.641 after 16,600 steps (an earlier build, differing only in round-off: 0.636,
  /// 13,400). On the 188-pinacoid pile (4 x 4, h = 8, seed 1) c = 0.4 below 0.01 reached SPEC 6.1
  /// at t = 50.0; undamped, the same build ended its 60 t0 at force / moment / kinetic ratios
  /// 2.1e-4 / 7e-5 / 4e-7.
  double dampingSpeed = 0.01;
  /// ["threads"] most OpenMP threads of a phase [-], >= 1 (`--threads` sets it unless the backend
  /// options name their own). The broad and narrow phases and the MPRGP passes use up to this
  /// many; each phase times its team against one thread and keeps the faster (thread_choice.hpp).
  /// Results are the same bits for any value. Gauss-Seidel (nlgs) stays sequential.
  int threads = 1;

  /// Throws std::invalid_argument naming the field if a value is out of range.
  void validate() const;
};

void to_json(nlohmann::json& j, const NscdSettings& s);
std::string toString(SolverKind k);
std::string toString(ExpansionKind k);
std::string toString(PreconditionerKind k);
/// Defaults of the solver-dependent settings (tolerance, max_iterations) for `kind`.
NscdSettings defaultsFor(SolverKind kind);
/// Reads the keys that are present (missing ones keep their defaults); throws
/// std::invalid_argument for an unknown key, a value of the wrong type, or one out of range.
NscdSettings settingsFromJson(const nlohmann::json& j);

}  // namespace confpack::nscd
