#pragma once
// The contact region of two convex polyhedra and its points (steps 3 and 4 of collidePolyhedra).
//
// Features. The contact feature of a body along the normal n is the set of its vertices within
//     eps = max(sin(angleTol), 1e-9) * 2 R     [d_L]   (R: the body's bounding radius)
// of its support plane: 1 vertex -> Vertex, 2 -> Edge, >= 3 -> Face. A face tilted by less than
// angleTol from the contact plane is thus seen as a face.
//
// Region. The two features projected on the contact plane (frame (u, v) with u x v = n) intersect
// in a point, a segment, or a convex polygon (Sutherland-Hodgman clipping); its dimension is the
// contact type: polygon -> Triple, segment -> Double, point -> Simple. Vertex-anything and
// crossing edge-edge -> Simple, edge-face -> Double, face-face -> Triple. Two parallel edges lying
// on each other touch along a segment: a line contact, Double (2 points) like edge-face, since it
// removes the same 2 freedoms.
//
// Points. They lie on the contact plane midway between the two surfaces: at lateral point x the
// surfaces are at heights h_A(x), h_B(x) along n, the point at (h_A + h_B) / 2 and its gap
// h_B - h_A (the gaps differ across a tilted face-face contact). Single-point contacts whose
// features do not overlap in projection (vertex-vertex, vertex-edge, or a large angleTol) use the
// closest pair of points of the two features instead: point = their midpoint,
// gap = n.(onB - onA). A face-face contact keeps every vertex of the clipped polygon as a point (up
// to kMaxPolyhedronContactPoints = 8, the most two quadrilateral pinacoid faces give), each with
// its own gap: the minimum of the gap over the polygon is at a vertex, so no part of the region
// can pass through. Two smaller choices failed in nscd: 3 points of a rectangle-on-rectangle
// contact put the centre of mass on an edge of the support triangle (marginal static support);
// 4 points (the deepest vertex and the 3 of largest area with it) let the dropped vertices sink
// unseen into the other grain as it rocked, and each time one came back into the chosen 4 its
// overlap was corrected with a kick (on a 188-pinacoid pile one grain rocked with period 2 for
// 60 t0, the force ratio stuck near 0.2). A polygon of more than 8 vertices (faces of more than 4
// vertices, only possible for other convex shapes) is reduced to 4: its deepest vertex and the 3
// others of largest convex-hull area with it.
//
// Points within reach (pointReach > 0, what a solver asks for). The features above are the
// contact's geometric reading, at the type's tolerance; a solver needs instead every point that
// can touch within a step. An edge 0.3 degrees off a face reads as a vertex on the face, one
// point, and its other end, 3.6e-3 d higher, is unseen: in a 338-pinacoid pile such a pair was
// read in turn as one point and as two, the free end sank up to 5.6e-3 d into the face, the grains
// rocked in 2-cycles and the pile never came to rest (docs/pinacoid-shape.md). So each body also
// gets a reach face: through its support vertex, the face with the most vertices within pointReach
// of its support plane. The points are then the vertices of the overlap of the two reach faces'
// projections, those within pointReach of the deepest point, each with the exact gap between the
// two face planes (both planes are exact there: a face whose normal points towards the other body
// is that body's surface over its own projection). They replace the points above when they hold
// the deepest of them, i.e. when the reach faces cover the contact; the type and the features stay
// the geometric ones. With pointReach = the alert distance that pile comes to rest.
#include <span>

#include "collision/world_polyhedron.hpp"

namespace confpack::collision {

/// The support feature of a body along a unit direction.
struct SupportSet {
  VertexArray<int> verts;  ///< indices of the vertices within eps of the support plane
  Feature feature{};       ///< 1 vertex -> Vertex, 2 -> Edge, >= 3 -> Face
};

/// Support feature of w along dir (unit): the vertices with dir.x >= max_w dir.x - eps [d_L].
SupportSet supportSet(const WorldPolyhedron& w, const Vec3& dir, double eps);

/// z component of the cross product of two lateral vectors.
inline double cross2(const Vec2& a, const Vec2& b) {
  return a.x() * b.y() - a.y() * b.x();
}

/// Counter-clockwise convex hull of lateral points (Andrew's monotone chain; collinear points
/// dropped, two equal points one): written here because none of the project's libraries offers
/// a 2D hull of a handful of points.
Polygon2 convexHull(Polygon2 pts);

/// n / |n|; throws std::invalid_argument naming `who` unless n is non-zero and finite.
Vec3 unitOrThrow(const Vec3& n, const char* who);

/// Signed area of a polygon (> 0 counter-clockwise) [d_L^2].
double polygonArea(std::span<const Vec2> p);

/// Sutherland-Hodgman: `subject` clipped by the convex counter-clockwise polygon `clipper`.
Polygon2 clipPolygon(Polygon2 subject, std::span<const Vec2> clipper);

/// The contact plane's frame: n the normal, (u, v) its lateral axes.
struct Frame {
  Vec3 n, u, v;  // n = u x v
  Vec2 lateral(const Vec3& x) const { return {u.dot(x), v.dot(x)}; }
  Vec3 world(const Vec2& x, double h) const { return x.x() * u + x.y() * v + h * n; }
};

/// The frame of unit normal n (u = any unit vector orthogonal to n, v = n x u).
Frame frameFor(const Vec3& n);

/// The vertices of w on the far side of the level `level` along fr.n, `sign` 1: n.x >= level (a
/// body below the contact plane), -1: n.x <= level (a body above it), projected on the plane: a
/// body's vertices within a band of the plane, or past it.
Polygon2 touchingProjections(const WorldPolyhedron& w, const Frame& fr, double level, double sign);

/// Indices of the contact points kept from a region's candidates (lateral positions pts and
/// gaps): all of them up to kMaxPolyhedronContactPoints, else 4 (the deepest and the 3 others of
/// largest convex-hull area with it), in their input order.
SmallVector<int, kMaxPolyhedronContactPoints> keptPoints(std::span<const Vec2> pts, std::span<const double> gaps);

/// Features, region, type and points of the pair (A, B) for a given unit normal (A towards B) and
/// gap [d_L]; angleTol [rad] is the tolerance of the support features; pointReach [d_L] > 0 asks
/// for the points within reach (above) instead of the features' own.
PolyhedronContact buildContact(const WorldPolyhedron& A, const WorldPolyhedron& B, const Vec3& normal, double gap,
                               double angleTol, double pointReach = 0.0);

}  // namespace confpack::collision
