#pragma once
// Settings of the Bullet backend (docs/model.md, "Bullet: sequential impulses"), with their JSON
// round trip. No Bullet header here: the values are plain numbers that bullet_backend.cpp copies
// into btContactSolverInfo, btDispatcherInfo and the persistent manifolds. Every key of the options
// JSON is a field below; unknown keys are refused so that a typo never silently runs with a
// default.
//
// The defaults aim at low interpenetration in dense piles under gravity with dt ~ 1e-3 t0.
// Measured with them (tests/backends, the conformance suite, small piles):
// - sphere contacts start 0.02 d before touching, so spheres stop at the surface: largest
//   overlap ever 1.5e-7 d while a 163-sphere deposit compacts;
// - polyhedron contacts (Bullet's SAT + clipping) appear only once hulls overlap: impacts
//   overlap by up to ~1e-2 d (the approach per step), removed by the erp bias within a few
//   steps; at rest the mean overlap is ~1e-7 d and the largest ~1e-5 d (60 pinacoids);
// - with those overlaps below 0.02 d the split impulse never engages; a threshold of 0 (all
//   corrections by split impulse) left 20x larger resting overlaps in the same pinacoid pile;
// - statics: 10-bead column 7.7e-7 (dt 1e-3) and 1.1e-6 (dt 4e-3) relative error on k m g,
//   settled pile floor reaction 8.7e-9 of the weight, resting sphere / pinacoid m g to 1e-16 /
//   3e-11; frictional wall (rolling and sliding spheres) to 1e-13.
#include <nlohmann/json.hpp>

#include "core/settings_table.hpp"

namespace confpack::bullet {

/// Options of the bullet backend. JSON keys in brackets.
struct BulletSettings {
  /// ["iterations"] cap on the sequential-impulse sweeps per step
  /// (btContactSolverInfo::m_numIterations) [-], >= 1. Bullet's default of 10 leaves a column of
  /// beads elastic; a 91-sphere pile compacting in `confpack run` used 187 sweeps per step on
  /// average with this cap (the early exit below usually ends them sooner once settled).
  int iterations = 200;
  /// ["residual_threshold"] early exit: the sweeps stop when the largest velocity correction of
  /// one sweep, relative to the velocity gravity adds in one step (|g| dt), falls below this
  /// value [-], >= 0. Bullet compares (residual_threshold |g| dt)^2 with its
  /// m_leastSquaresResidual (max over rows of (delta impulse x effective inverse mass)^2). The
  /// contact forces are then converged to about this relative accuracy: a column of 10 beads
  /// gives the k m g law to 1e-6 with 1e-6, to machine precision with 0 (measured).
  /// 0 = always run `iterations` sweeps.
  double residualThreshold = 1e-6;
  /// ["split_impulse"] correct overlaps deeper than split_impulse_penetration_threshold with a
  /// separate "push" velocity that moves the grains without adding momentum (Bullet's split
  /// impulse), instead of a Baumgarte velocity bias.
  bool splitImpulse = true;
  /// ["split_impulse_penetration_threshold"] overlaps deeper than this (a negative distance)
  /// are corrected by split impulse with erp2; shallower ones by a Baumgarte bias with erp
  /// inside the velocity solve [d_L], <= 0. Bullet's default is -0.04.
  double splitImpulsePenetrationThreshold = -0.02;
  /// ["split_impulse_turn_erp"] fraction of the split-impulse turn velocity applied to the
  /// orientation [-], in [0, 1].
  double splitImpulseTurnErp = 0.1;
  /// ["erp"] Baumgarte error reduction of overlaps shallower than the split threshold (or of
  /// all overlaps when split impulse is off): the solver asks for a separation velocity
  /// erp x overlap / dt [-], in [0, 1].
  double erp = 0.2;
  /// ["erp2"] error reduction of the split-impulse push for deep overlaps [-], in [0, 1].
  double erp2 = 0.2;
  /// ["global_cfm"] constraint force mixing (regularisation, 0 = hard contact) [-], >= 0.
  double globalCfm = 0.0;
  /// ["sor"] successive over-relaxation factor of every row [-], in (0, 2).
  double sor = 1.0;
  /// ["linear_slop"] distance added to every contact distance before the position correction:
  /// overlaps smaller than it are tolerated [d_L], >= 0.
  double linearSlop = 0.0;
  /// ["warm_starting_factor"] fraction of the previous step's normal impulse that starts each
  /// contact row [-], in [0, 1]. (The solver's warm-starting flag stays on because Bullet only
  /// writes the impulses back into the manifold points, where contacts() reads them, when it is
  /// set; 0 here disables warm starting.) Bullet does not warm start friction rows.
  double warmStartingFactor = 1.0;
  /// ["contact_breaking_threshold"] a manifold point is created when the gap is below this and
  /// dropped when the gap (or the tangential drift of its two anchors) exceeds it; also the AABB
  /// inflation of the broad phase [d_L], > 0.
  double contactBreakingThreshold = 0.02;
  /// ["friction_directions"] 1 or 2 friction rows per contact point. One row (Bullet's default)
  /// along the current sliding direction leaves a resting contact free to creep sideways; two
  /// rows approximate the Coulomb disc by a square of half-side mu f_n. Only side-wall contacts
  /// have mu > 0; on all others the rows are clamped to zero by their bounds.
  int frictionDirections = 2;
  /// ["skip_zero_friction_rows"] build no friction rows for contacts whose friction
  /// coefficient is 0 (all but the side-wall contacts). Bullet clamps such rows to zero in every
  /// sweep, so the physics is bitwise the same (tested); a step of a 163-sphere pile is about
  /// 1.5 times faster (measured). Off = Bullet's stock row layout.
  bool skipZeroFrictionRows = true;
  /// ["sat_convex"] polyhedron-polyhedron contact normal from Bullet's exact separating-axis
  /// test (true) rather than GJK/EPA (false); the contact points come from face clipping in
  /// both cases.
  bool satConvex = true;
  /// ["plane_perturbation_iterations"] a polyhedron touching a wall gets extra contact points by
  /// rotating it slightly this many times and taking the support point again (Bullet's
  /// multipoint plane contact) [-], >= 0. Without it a face resting on the floor is held by one
  /// point and rocks.
  int planePerturbationIterations = 3;
  /// ["plane_perturbation_min_points"] perturb only while the wall manifold has fewer points
  /// than this [-], >= 0.
  int planePerturbationMinPoints = 3;
  /// ["randomize_order"] random row order in every sweep (SOLVER_RANDMIZE_ORDER). Off: the
  /// order is deterministic, so a run is bitwise reproducible.
  bool randomizeOrder = false;
  /// ["manifolds_per_grain"] size of Bullet's preallocated manifold and algorithm pools, per
  /// grain [-], >= 1. Pools that overflow fall back to the heap (slower, still correct).
  int manifoldsPerGrain = 4;

  /// Throws std::invalid_argument naming the field if a value is out of range.
  void validate() const;
};

/// The keys of BulletSettings with their units, ranges and meaning (core/settings_table.hpp).
const core::SettingsTable<BulletSettings>& settingsTable();
void to_json(nlohmann::json& j, const BulletSettings& s);
/// Reads the keys that are present (missing ones keep their defaults); throws
/// std::invalid_argument for an unknown key, a value of the wrong type, or one out of range.
BulletSettings bulletSettingsFromJson(const nlohmann::json& j);

}  // namespace confpack::bullet
