#pragma once
// The contact rows of an nscd step: the unknowns, the kinematics and the contact law that the
// three solvers of contact_solver.hpp (nlgs_solver.hpp, mprgp_solver.hpp, ipm_solver.hpp) solve,
// built once per step and shared by them.
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
// Under contact_law "velocity" c = max(0, g_m / dt): an overlap is held, never removed
// (nscd_settings.hpp).
//
// Side-wall friction (Coulomb, e_t = 0): ||r_t|| <= mu r_n; u_t = 0 if ||r_t|| < mu r_n, otherwise
// r_t = -mu r_n u_t / ||u_t||.
//
// Multi-point contacts (double, triple) are solved point by point as independent rows sharing the
// normal: the total force and moment of the contact converge, while their split between points is
// whatever the sweep reaches (the static problem leaves it undetermined).
//
// Sweep order: frictionless rows sorted by the height z of their contact point, lowest first (ties by
// bodies a, b, then contact and point index), then the side-wall friction rows in contact order.
// The order depends only on the configuration: bitwise determinism. Bottom to top needs fewer
// sweeps than contact order near jamming; top to bottom does not (a velocity-level sweep does not
// carry weight down a chain in one pass: the top contact of a free-falling column sees zero
// relative velocity). Measurements: docs/performance.md, "nscd settings: the measurements behind
// the defaults".
//
// Sweep blocks (for the Gauss-Seidel preconditioner of mprgp, mprgp_solver.hpp).
//   A sweep is serial by nature; for two threads the rows are ordered in blocks (build()): on a
//   box with L_x >= 16 lever arms, first the rows of the two halves of the box along x, less the
//   strips within a lever arm of their edges, each half bottom to top, then the strip rows bottom
//   to top. The halves share no grain, so two threads sweep them at once and give the bits of
//   one: the order depends on the configuration only, never on the thread count. On one thread
//   it costs a few per cent more iterations; the passes around the solve stay on one thread, as
//   they stream memory, whose bandwidth a second core raises only 1.4 times (docs/performance.md,
//   "Two threads").
#include <array>
#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include "backends/nscd/contact_cache.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "core/walls.hpp"

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

/// A frictionless contact point (grain-grain, floor, or a side wall without friction).
struct NormalRow {
  core::Vec3 n, axn, bxn, iaAxn, ibBxn;  // Jacobian pieces: n, l_a x n, l_b x n, I_a^-1 (l_a x n), ...
  double invMa = 0.0, invMb = 0.0;
  double invW = 0.0;  // 1 / W_nn
  double bias = 0.0;  // c of the contact law [d_L / t0]
  double r = 0.0;     // impulse
  int a = 0, b = 0;   // body indices (b = the static body for walls)
  double z = 0.0;     // height of the contact point
  double x = 0.0;     // its abscissa (the sweep's blocks)
  int segment = 0;    // sweep block (see ContactRows::build)
  int c = 0, p = 0;   // contact and point index (sort ties)
};

/// A point on a side wall with friction: b is static.
struct FrictionRow {
  core::Vec3 n, t1, t2, axn, axt1, axt2, iaAxn, iaAxt1, iaAxt2;
  double invMa = 0.0, invWnn = 0.0, invWt = 0.0, bias = 0.0, mu = 0.0;
  double rn = 0.0, rt1 = 0.0, rt2 = 0.0;
  int a = 0;
};

/// Relative normal velocity at a point, without the bias c: u_n = n.(v_b - v_a) + (l_b x n).w_b -
/// (l_a x n).w_a, for any row carrying the Jacobian pieces n, axn, bxn (a NormalRow, or a solver's
/// own copy of one). One expression for every solver, so they agree on its bits.
template <class Row>
inline double normalVelocity(const Row& row, const BodyVelocity& va, const BodyVelocity& vb) {
  return row.n.dot(vb.v - va.v) + row.bxn.dot(vb.w) - row.axn.dot(va.w);
}

/// The same at a side-wall point: the wall does not move, u_n = -(n.v_a + (l_a x n).w_a).
inline double normalVelocity(const FrictionRow& row, const BodyVelocity& va) {
  return -(row.n.dot(va.v) + row.axn.dot(va.w));
}

/// Tangential update of a side-wall friction point at its current normal impulse: one local
/// Gauss-Seidel step, over-relaxed by `omega`, projected on the Coulomb disc ||r_t|| <= mu r_n
/// (nlgs_solver.hpp states it), applied to the velocity of its grain `va`. Returns the change
/// (d1, d2). Used by every solver.
std::pair<double, double> updateTangent(FrictionRow& row, BodyVelocity& va, double omega = 1.0);

/// The rows of one step's contact points, shared by the two solvers.
/// Owns the rows (frictionless ones in sweep order, side-wall friction ones in contact order), the
/// map from (contact, point) to its row, the sweep order and its two blocks, and the solved normal
/// impulses in contact order. Verbs, once per step in this order: build, warmStart, a solver's
/// solve (nlgs_solver.hpp, mprgp_solver.hpp), exportImpulses; normalImpulse, tangentImpulse,
/// rowCount and sweepBlockBodies read the result.
class ContactRows {
 public:
  /// Builds the rows of every contact point: lever arms from `positions` (q_m), Delassus diagonal,
  /// gap-correction bias. `bodies` has one entry per grain plus a last, static one (zero inverse
  /// mass) standing for the walls; `walls` gives a wall contact its friction (mu_w on side walls).
  /// The rows are built for settings.solver: with mprgp, in sweep blocks, and with the warm
  /// start's normal impulses left to the solve (warmNormalsInSolve()).
  void build(const std::vector<ContactGeometry>& contacts, const std::vector<core::Vec3>& positions,
             const std::vector<BodyInverseMass>& bodies, const core::BoxDef& box, const core::WallMaterial& walls,
             double dt, const NscdSettings& settings);
  /// Sets the impulses from the cache (scaled to this dt) and applies them to the velocities;
  /// with mprgp (the solver of the last build()), only the tangential ones: its solve applies the
  /// normal impulses in its own pass over the bodies.
  void warmStart(const ContactCache& cache, const std::vector<ContactGeometry>& contacts, double dt,
                 std::vector<BodyVelocity>& velocities);
  /// Writes the solution into cache entries (same order as the contacts).
  void exportImpulses(const std::vector<ContactGeometry>& contacts, std::vector<CachedContact>& out) const;

  /// Impulses of contact c, point p, after a solve: normal and tangential (world vector).
  double normalImpulse(int c, int p) const;
  core::Vec3 tangentImpulse(int c, int p) const;
  int rowCount() const { return static_cast<int>(normalRows_.size() + frictionRows_.size()); }
  /// No row has a lever arm across its normal (|l x n| of a sphere row is ~1e-16, a pinacoid's
  /// ~0.1): no normal impulse turns a body, and the normal solves leave the angular velocities
  /// out. Side-wall friction does turn spheres; its tangential pass (updateTangent) keeps them.
  bool turnsNoBody() const;
  /// The grains touched by the rows of each of the two sweep blocks of the last build(), sorted,
  /// without `world` (the static body); both empty when the rows are not split. The blocks are
  /// swept at once by two threads, so they must share none.
  std::array<std::vector<int>, 2> sweepBlockBodies(int world) const;

  // What the solvers work on. Frictionless rows in sweep order; rows [0, sweepBlockEnd(0)) and
  // [sweepBlockEnd(0), sweepBlockEnd(1)) share no grain, the rest is swept serially.
  std::span<NormalRow> normalRows() { return normalRows_; }
  std::span<const NormalRow> normalRows() const { return normalRows_; }
  std::span<FrictionRow> frictionRows() { return frictionRows_; }
  std::span<const FrictionRow> frictionRows() const { return frictionRows_; }
  int sweepBlockEnd(int block) const { return sweepBlockEnd_[block]; }
  /// Whether warmStart() left the normal impulses out of the velocities, for the solve to apply.
  bool warmNormalsInSolve() const { return warmNormalsInSolve_; }
  /// Records the solved normal impulse of every frictionless row, `impulse(k)` for row k in sweep
  /// order, in contact order: normalImpulse() and exportImpulses() read every contact's points,
  /// and through the rows in sweep order each read missed the cache.
  template <class Impulse>
  void storeNormalImpulses(const Impulse& impulse) {
    impulseOfRow_.resize(normalRows_.size());
    for (std::size_t k = 0; k < normalRows_.size(); ++k)
      impulseOfRow_[static_cast<std::size_t>(sortKeys_[k].index)] = impulse(k);
  }

 private:
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
  // set by the solve (storeNormalImpulses()).
  std::vector<double> impulseOfRow_;
  // Sweep blocks of the normal rows (build()): [0, e0) and [e0, e1) share no grain; [e1, m) is
  // swept serially. e0 = e1 = 0 when the box is not split.
  int sweepBlockEnd_[2] = {0, 0};
  std::vector<NormalRow> sorted_;  // scratch of build(), kept to avoid reallocations
  // A row's place in the sweep order (build()).
  struct SortKey {
    int segment;
    double z;
    int a, b, c, p;
    int index;
  };
  std::vector<SortKey> sortKeys_;
  // The warm start's normal impulses are applied to the velocities by MPRGP's solve, one pass per
  // body over its scatter entries, on the solver's team, instead of by warmStart(), contact by
  // contact through the rows in sweep order (a cache miss per point).
  bool warmNormalsInSolve_ = false;
};

}  // namespace confpack::nscd
