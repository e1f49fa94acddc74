#pragma once
// A placed convex polyhedron in world coordinates, with the topology the narrow phase needs: the
// shared input of the separating-axis test (separating_axis), the exact distance
// (polyhedron_distance) and the contact region (contact_region), all behind polyhedron_contact.
//
// Face f is the half-space boundary n_f . x = off_f (n_f outward, unit); with the body-to-world
// map x = t + R x_b, n_f = R n_f,b and off_f = off_f,b + n_f . t. Each edge stores its two
// adjacent faces and the normal n[face1] x n[face0] of its arc on the Gauss map (the unit sphere
// of face normals), for the Minkowski-face test of separating_axis. Lengths in d_L.
//
// Inline capacities (SmallVector): a pinacoid has 8 vertices, 8 faces of at most 4 vertices and
// 14 edges, so the narrow phase allocates nothing for it; a larger shape spills to the heap.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "collision/polyhedron_contact.hpp"

namespace confpack::collision {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
// Lengths below kRelativeLengthTol x (size of the pair) are zero: a contact region thinner than
// that is a segment, shorter than that a point. Far above rounding (1e-16), far below any physical
// length of the problem (the alert distance is ~1e-3 to 1e-2 d).
inline constexpr double kRelativeLengthTol = 1e-9;
// Edge pairs whose cross product is shorter than this (relative, i.e. sin of their angle) give no
// separating axis: the face axes already cover parallel edges.
inline constexpr double kParallelEdgeSin = 1e-9;

inline constexpr std::size_t kInlineVertices = 16;  // vertices, faces, polygon vertices
inline constexpr std::size_t kInlineEdges = 32;

template <class T>
using VertexArray = SmallVector<T, kInlineVertices>;
using Vec2 = Eigen::Vector2d;
using Polygon2 = VertexArray<Vec2>;

// A polyhedron in world coordinates with the topology the narrow phase needs.
struct WorldPolyhedron {
  const ConvexPolyhedron* shape = nullptr;
  VertexArray<Vec3> v;                                      // world vertices
  VertexArray<Vec3> n;                                      // world outward face normals
  VertexArray<double> off;                                  // n.x = off on the face
  SmallVector<std::array<int, 2>, kInlineEdges> edgeFaces;  // the two faces adjacent to each edge
  SmallVector<Vec3, kInlineEdges> edgeArc;                  // n[face1] x n[face0]: the edge's Gauss-map arc normal
  Vec3 centre = Vec3::Zero();                               // an interior point (vertex mean)
  double radius = 0.0;                                      // bounding radius of the shape

  /// Vertices, face normals and offsets in world coordinates; with withTopology also each edge's
  /// two faces and its Gauss-map arc normal (the separating-axis test needs them, a plane or a
  /// sphere contact does not).
  explicit WorldPolyhedron(const PlacedPolyhedron& p, bool withTopology = true) { assign(p, withTopology); }
  /// Empty (no shape), to be filled by assign: the nscd narrow phase keeps one per grain.
  WorldPolyhedron() = default;
  /// Refills this one for `p`, as the constructor does (no allocation for a pinacoid).
  void assign(const PlacedPolyhedron& p, bool withTopology = true);

  int edgeIndex(int i, int j) const {
    const int lo = std::min(i, j), hi = std::max(i, j);
    const auto& edges = shape->edges();
    for (std::size_t e = 0; e < edges.size(); ++e)
      if (edges[e][0] == lo && edges[e][1] == hi) return static_cast<int>(e);
    return -1;
  }
  double maxAlong(const Vec3& d) const {
    double m = -kInf;
    for (const Vec3& x : v) m = std::max(m, d.dot(x));
    return m;
  }
  double minAlong(const Vec3& d) const {
    double m = kInf;
    for (const Vec3& x : v) m = std::min(m, d.dot(x));
    return m;
  }
  // Tolerance on heights for the support feature: a face tilted by angleTol spans at most
  // sin(angleTol) x (its diameter <= 2R) in height. Never below the rounding of the heights
  // (kRelativeLengthTol): a face exactly normal to n must still read as a face at angleTol = 0.
  double featureEps(double angleTol) const {
    return std::max(std::sin(std::max(angleTol, 0.0)), kRelativeLengthTol) * 2.0 * radius;
  }
};

/// True if the projection of x on the plane of face f lies inside the face polygon (closed).
bool projectsInsideFace(const WorldPolyhedron& w, int f, const Vec3& x);

}  // namespace confpack::collision
