#pragma once
// Exact volumes of grains cut by planes and of grain-grain overlaps, for either shape: spheres
// by the closed forms of sphere_geometry, pinacoids by exact convex clipping
// (collision/polyhedron_clip.hpp). Every volume-based measurement goes through here.
#include <span>
#include <vector>

#include "collision/polyhedron_clip.hpp"
#include "core/grain.hpp"

namespace confpack::analysis {

/// A pinacoid grain's polyhedron kept alive next to its placement (PlacedPolyhedron does not
/// own its shape).
struct PlacedGrain {
  core::ConvexPolyhedron shape;
  collision::PlacedPolyhedron placed;

  /// Places g's polyhedron at `position` (default: the grain's own position). Pinacoids only.
  explicit PlacedGrain(const core::Grain& g);
  PlacedGrain(const core::Grain& g, const core::Vec3& position);
  PlacedGrain(const PlacedGrain& o) : shape(o.shape), placed(o.placed) { placed.shape = &shape; }
  PlacedGrain& operator=(const PlacedGrain&) = delete;
};

/// Volume of grain g between the planes x[axis] = lo and x[axis] = hi [d_L^3] (no periodic
/// wrapping: the grain as placed).
double grainSlabVolume(const core::Grain& g, int axis, double lo, double hi);

/// Volumes of g in the consecutive slabs [edges[k], edges[k+1]) along axis, with the periodic
/// images g + m * period (m = -1, 0, 1) added when period > 0, so that a grain straddling a
/// periodic boundary fills the slices on both sides. Returns edges.size() - 1 values.
std::vector<double> grainSlabVolumes(const core::Grain& g, int axis, std::span<const double> edges,
                                     double period = 0.0);

/// Volume of g inside the axis-aligned box [lo, hi] [d_L^3]. Pinacoids only (an exact
/// sphere-box volume is not implemented): throws std::invalid_argument for a sphere.
double grainBoxVolume(const core::Grain& g, const core::Vec3& lo, const core::Vec3& hi);

/// Overlap volume of grains a and b, with b placed at a.position + separation (the caller's
/// minimum-image separation) [d_L^3]. Spheres: exact lens; pinacoids: exact convex
/// intersection. A sphere-pinacoid pair (never produced by the study's mixtures) throws
/// std::invalid_argument.
double grainOverlapVolume(const core::Grain& a, const core::Grain& b, const core::Vec3& separation);

/// The intersection of two placed pinacoids as a polytope (for bounds and further clipping).
collision::ConvexPolytope pinacoidIntersection(const collision::PlacedPolyhedron& a,
                                               const collision::PlacedPolyhedron& b);

}  // namespace confpack::analysis
