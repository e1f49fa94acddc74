#pragma once
// Narrow phase of the nscd backend: exact contact geometry (plane, points, gaps) for a candidate
// pair in the predicted configuration q_m, dispatched on the pair of shapes by an if/else over
// the two shape kinds (sphere-sphere, polyhedron-polyhedron, polyhedron-sphere; walls apart): with
// two shapes that is all a pair table would hold.
#include <array>
#include <cstdint>
#include <vector>

#include "backends/nscd/broad_phase.hpp"
#include "backends/nscd/thread_choice.hpp"
#include "collision/polyhedron_contact.hpp"
#include "collision/world_polyhedron.hpp"
#include "core/box.hpp"
#include "core/contact.hpp"
#include "core/grain.hpp"

namespace confpack::nscd {

/// Largest number of points of one contact: every vertex of a face-face clip of two pinacoids.
inline constexpr int kMaxContactPoints = collision::kMaxPolyhedronContactPoints;

/// One contact plane between grain a and grain b (or a wall, b < 0) with its points.
struct ContactGeometry {
  int a = 0;
  int b = 0;               ///< grain index, or a core::WallId value
  std::int8_t shiftX = 0;  ///< b's image: position_b + shiftX L_x e_x + shiftY W e_y
  std::int8_t shiftY = 0;
  core::ContactType type = core::ContactType::Simple;
  std::uint32_t feature = 0;                ///< feature pair (polyhedra), part of the cache key; 0 for spheres
  core::Vec3 normal = core::Vec3::UnitZ();  ///< unit, from a towards b
  int pointCount = 0;
  std::array<core::Vec3, kMaxContactPoints> points{};  ///< world frame, near a (midway across the gap)
  std::array<double, kMaxContactPoints> gaps{};        ///< signed gap at each point [d_L]
};

/// Sphere-sphere: gap = |x_b - x_a| - r_a - r_b, normal along the centre line, one point midway
/// across the gap. Returns false if the gap is not below `alert`.
bool collideSphereSphere(const core::Vec3& pa, double ra, const core::Vec3& pbImage, double rb, double alert,
                         ContactGeometry& out);

/// Sphere-wall: the wall is the plane through box.wallPoint(w) with inward normal
/// BoxDef::wallNormal(w); the contact normal points into the wall. One point.
bool collideSphereWall(const core::Vec3& pa, double ra, core::WallId w, const core::BoxDef& box, double alert,
                       ContactGeometry& out);

/// Packs the feature pair of a polyhedron contact into a cache-key word (kind and index of each).
std::uint32_t featureKey(const collision::Feature& a, const collision::Feature& b);

/// Copies a polyhedron contact (collision/polyhedron_contact.hpp) into `out`; `flip` reverses the
/// normal and swaps the features (when the routine was called with the bodies exchanged).
void fromPolyhedronContact(const collision::PolyhedronContact& pc, bool flip, ContactGeometry& out);

/// Shape data of every grain, and the dispatch over pairs of shapes.
class NarrowPhase {
 public:
  /// Fewer candidate pairs than this per thread and collideAll runs on fewer threads (the
  /// parallel region and the join copy cost more than they share). Speed only, never output.
  static constexpr std::size_t kMinPairsPerThread = 2000;

  /// Throws std::invalid_argument if a grain has a size that is not a positive number.
  /// commonPlaneBand > 0 reads polyhedron pairs as LMGC90's common plane does
  /// (collision::collideCommonPlane, with that band); 0, the default, exactly.
  NarrowPhase(const core::BoxDef& box, const std::vector<core::Grain>& grains, double alertFraction,
              double commonPlaneBand = 0.0);

  /// Interaction radius of grain i for the broad phase: bounding radius + alert distance.
  double reach(int i) const { return radius_[i] + alertFraction_ * size_[i]; }
  double maxReach() const;

  /// Appends the contact of a candidate pair (if its gap is within the alert distance).
  void collidePair(const CandidatePair& pair, const std::vector<core::Vec3>& positions,
                   const std::vector<core::Quat>& orientations, std::vector<ContactGeometry>& out) const;
  /// Appends the contacts of grain i with the floor and the side walls.
  void collideWalls(int i, const std::vector<core::Vec3>& positions, const std::vector<core::Quat>& orientations,
                    std::vector<ContactGeometry>& out) const;

  /// Replaces `out` with every contact of a step: those of the candidate pairs in pair order,
  /// then those of every grain with the walls in grain order (the solver's row order and the
  /// cache depend on it). `threads` > 1 splits both loops into contiguous ranges on that many
  /// OpenMP threads and joins the ranges in order (a ThreadChoice times the team against one
  /// thread and keeps the faster): `out` is the same, bit for bit, for any thread count. No
  /// allocation once the buffers have grown.
  void collideAll(const std::vector<CandidatePair>& pairs, const std::vector<core::Vec3>& positions,
                  const std::vector<core::Quat>& orientations, std::vector<ContactGeometry>& out, int threads = 1);

 private:
  // collidePair, with the polyhedra of the grains in world coordinates taken from `world` (one
  // per grain, at `positions`) when it is not null, instead of placed again for each pair.
  void collidePairIn(const CandidatePair& pair, const std::vector<core::Vec3>& positions,
                     const std::vector<core::Quat>& orientations, const std::vector<collision::WorldPolyhedron>* world,
                     std::vector<ContactGeometry>& out) const;
  // Places grain i's polyhedron in world_ (nothing for a sphere).
  void placeGrain(int i, const std::vector<core::Vec3>& positions, const std::vector<core::Quat>& orientations);

  // Each pinacoid in world coordinates for the step collideAll is detecting: a grain has some ten
  // candidate pairs in a pile, and placing its polyhedron for each of them (vertices, normals,
  // edge topology) took a tenth of a pinacoid pile's fall (measured).
  std::vector<collision::WorldPolyhedron> world_;
  // Contacts found by one thread (thread 0 writes its pair contacts straight into `out`).
  struct ThreadContacts {
    std::vector<ContactGeometry> pairs, walls;
    std::size_t pairStart = 0, wallStart = 0;  // where they go in `out`
  };
  std::vector<ThreadContacts> threadContacts_;
  ThreadChoice choice_;  // team against one thread, timed (for the last `threads` asked)
  /// Some grain is a polyhedron. Sphere-only systems collide on one thread: a sphere pair costs
  /// ~10 ns, so the whole phase (~60 us a step for 3,600 spheres) is less than the parallel region
  /// and the join copy (2 threads were slower).
  bool hasPolyhedra_ = false;

  core::BoxDef box_;
  double alertFraction_ = 0.0;
  double commonPlaneBand_ = 0.0;  ///< > 0: polyhedron pairs read on the common plane
  std::vector<core::ShapeKind> shape_;
  std::vector<double> radius_;                ///< sphere radius or bounding radius [d_L]
  std::vector<double> size_;                  ///< d or L [d_L]
  std::vector<core::ConvexPolyhedron> poly_;  ///< body-frame shape of pinacoids (empty for spheres)
};

}  // namespace confpack::nscd
