#pragma once
// Exact volumes of convex polyhedra cut by half-spaces: grain-slab, grain-cell and grain-grain
// intersection volumes, no sampling (docs/model.md, "Interpenetration" and "Solid fraction").
//
// A convex polytope is kept as a list of face loops over a vertex array. Clipping by one plane
// splits every face loop (Sutherland-Hodgman on the face), shares the new vertex of a cut edge
// between its two faces, and closes the cut with a cap face whose vertices are ordered by angle
// around their mean in the plane (convexity makes the order unique). Vertices within a tolerance
// of the plane count as on it, so a plane through vertices or edges creates no slivers. The
// volume follows from the divergence theorem (fan tetrahedra from an interior reference point).
//
// Hand-written rather than taken from a library: CGAL's Nef polyhedra / exact kernels are orders
// of magnitude slower than the microseconds a lattice of thousands of cells per grain needs,
// and no packaged library clips a small convex polytope by a plane in place.
#include <functional>
#include <span>
#include <vector>

#include "collision/polyhedron_contact.hpp"

namespace confpack::collision {

/// Half-space {x : normal.x <= offset}. normal need not be unit (offset scales with it).
struct Plane {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
};

/// A convex polytope in world space (possibly empty): face f is the vertex loop
/// faceIndices[faceStarts[f] .. faceStarts[f+1]), counter-clockwise seen from outside.
struct ConvexPolytope {
  std::vector<Vec3> vertices;
  std::vector<int> faceIndices;
  std::vector<int> faceStarts{0};

  int faceCount() const { return static_cast<int>(faceStarts.size()) - 1; }
  bool empty() const { return faceCount() < 4; }
  /// Exact volume by the divergence theorem [d_L^3]; 0 if empty.
  double volume() const;
  /// Axis-aligned bounds of the vertices (lo, hi); meaningless if empty.
  std::pair<Vec3, Vec3> bounds() const;
};

/// The polytope of a placed polyhedron.
ConvexPolytope toPolytope(const PlacedPolyhedron& p);
/// in ∩ {normal.x <= offset} written into out (aliasing in and out works but copies). Clears
/// out if the result is empty.
void clip(const ConvexPolytope& in, const Plane& plane, ConvexPolytope& out);
/// Convenience: returns the clipped copy.
ConvexPolytope clipped(const ConvexPolytope& in, const Plane& plane);

/// Volume of p ∩ all half-spaces [d_L^3].
double clippedVolume(const PlacedPolyhedron& p, std::span<const Plane> halfSpaces);
/// Exact volume of the intersection of two convex polyhedra [d_L^3].
double intersectionVolume(const PlacedPolyhedron& a, const PlacedPolyhedron& b);
/// Volume of p within lo <= x[axis] <= hi (axis 0, 1 or 2) [d_L^3].
double slabVolume(const PlacedPolyhedron& p, int axis, double lo, double hi);
/// Volume of p inside the axis-aligned box [lo, hi] [d_L^3].
double boxVolume(const PlacedPolyhedron& p, const Vec3& lo, const Vec3& hi);

/// Volumes of p in the slabs [edges[i], edges[i+1]) along axis, in one sweep (successive cuts,
/// cheaper than one slabVolume per slab). edges must be increasing; returns edges.size()-1 values.
std::vector<double> slabVolumes(const PlacedPolyhedron& p, int axis, std::span<const double> edges);

/// Lattice of cubic cells of side h with cell (i, j, k) = origin + h [i, i+1) x [j, j+1) x [k, k+1)
/// (integer indices, any sign): calls fn(i, j, k, volume) for every cell that p overlaps with a
/// positive volume. Hierarchical (x slabs, then y columns, then z cells), so the cost grows with
/// the number of cut cells, not with 6 clips per cell.
void forEachCellVolume(const PlacedPolyhedron& p, const Vec3& origin, double h,
                       const std::function<void(int, int, int, double)>& fn);

}  // namespace confpack::collision
