#pragma once
// Exact narrow phase for convex polyhedra (pinacoids) and the shared geometric contact-type
// classifier (docs/model.md, "nscd: Moreau-Jean contact dynamics" and "Coordination number").
//
// Method, polyhedron-polyhedron (collidePolyhedra):
// 1. Separating-axis test over the face normals of both bodies and the cross products of every
//    edge pair (8 + 8 + 14 x 14 axes for two pinacoids; near-parallel edge pairs are skipped).
//    For any unit axis u, sep(u) = min_B u.x - max_A u.x is a lower bound of the distance, and
//    for overlapping polytopes the largest sep over these axes is exactly minus the penetration
//    depth (minimum translation distance). Face axes win ties against edge axes.
// 2. If the best sep is > 0 the bodies are disjoint and sep is only a lower bound (vertex-vertex,
//    vertex-edge and non-crossing edge-edge closest pairs are not on a SAT axis). The exact
//    distance is then computed by brute force over closest features (vertex-face projections and
//    all edge-edge segment pairs, pruned with the SAT bound), and the normal is the closest-point
//    direction. For face-face, edge-face and vertex-face configurations this direction is exactly
//    the face normal (face candidates win ties). For crossing edges, or when the closest pair is
//    nearly degenerate (an edge almost perpendicular to the normal, where the closest points are
//    ill-conditioned), the axis of larger support separation among the closest-point direction,
//    the edges' cross product and the SAT axis is kept: the true closest direction maximises it.
//    So the gap is never overestimated: it is exact when separated, exact depth when overlapping.
//    (Checked against FCL's libccd distance to 1e-9 in the tests. FCL 0.7's own GJK, GST_INDEP,
//    returned distances up to 2x too large for some pinacoid pairs: do not use it.)
// 3. The contact feature of each body along the normal is the set of its vertices within
//    eps = max(sin(angleTol), 1e-9) * (2 * boundingRadius) of its support plane: 1 vertex -> Vertex,
//    2 -> Edge, >= 3 -> Face. A face tilted by less than angleTol from the contact plane is thus
//    seen as a face. The contact region is the intersection of the two features projected on the
//    contact plane (a point, a segment, or a convex polygon from Sutherland-Hodgman clipping) and
//    its dimension gives the type: polygon -> Triple, segment -> Double, point -> Simple.
//    Vertex-anything and crossing edge-edge -> Simple; edge-face -> Double; face-face -> Triple.
//    Two parallel edges lying on each other touch along a segment: that is a line contact and is
//    reported as Double (2 points), the same as edge-face (it removes the same 2 freedoms).
// 4. Points lie on the contact plane midway between the two surfaces, with the gap along the
//    normal at each point (they differ for a tilted face-face contact). Single-point contacts
//    whose features do not overlap in projection (vertex-vertex, vertex-edge, or a large angleTol)
//    use the closest pair of points of the two features instead: point = their midpoint,
//    pointGap = normal.(onB - onA). A face-face contact keeps every vertex of the clipped
//    polygon as a point (up to kMaxPolyhedronContactPoints = 8, the most two quadrilateral
//    pinacoid faces can give), each with its own gap, not 3 points: two earlier choices
//    failed in nscd. 3 points of a rectangle-on-rectangle contact put the centre of mass on an
//    edge of the support triangle (marginal static support). 4 points (the deepest vertex and
//    the 3 of largest area with it) let the dropped vertices sink unseen into the other grain
//    as it rocked, and each time one came back into the chosen 4 its overlap was corrected with
//    a kick: on a 188-pinacoid pile one grain rocked with period 2 for 60 t0, with the force
//    ratio stuck near 0.2. The minimum of the gap over the contact polygon is at a vertex, so
//    with every vertex no part of the region can pass through. Triple contacts therefore carry
//    3 to 8 points. A polygon with more than 8 vertices (faces of more than 4 vertices, only
//    possible for other convex shapes) is reduced to 4: its deepest vertex and the 3 of largest
//    area with it.
//
// The same routine computes the type for every caller, so a contact is classified identically
// whichever backend produced it (classifyContact).
#include <optional>
#include <vector>

#include "core/contact.hpp"
#include "core/convex_polyhedron.hpp"
#include "core/small_vector.hpp"

namespace confpack::collision {

using core::ContactType;
using core::ConvexPolyhedron;
using core::Mat3;
using core::SmallVector;
using core::Vec3;

/// A convex polyhedron placed in the world: world = position + rotation * body.
/// Does not own the shape: the ConvexPolyhedron must outlive it.
struct PlacedPolyhedron {
  const ConvexPolyhedron* shape = nullptr;
  Vec3 position = Vec3::Zero();      ///< world position of the body origin [d_L]
  Mat3 rotation = Mat3::Identity();  ///< body-to-world rotation

  Vec3 toWorld(const Vec3& body) const { return position + rotation * body; }
  /// World coordinates of every vertex, in the shape's vertex order.
  std::vector<Vec3> worldVertices() const;
};

enum class FeatureKind { Vertex, Edge, Face };

/// A feature of a polyhedron: index into vertices(), edges() or faces() of its shape.
/// An Edge with index -1 means "two support vertices that are not joined by an edge" (only
/// possible with a large angular tolerance); the key is still deterministic.
struct Feature {
  FeatureKind kind = FeatureKind::Vertex;
  int index = 0;
  bool operator==(const Feature&) const = default;
};

/// Default angular tolerance [rad] under which a face (edge) counts as lying in the contact plane.
/// A solver may pass a larger one to the narrow phase (e.g. 0.05: more predictive points, each
/// with its own gap) while reporting types with classifyContact at the default.
inline constexpr double kFeatureAngleTol = 1e-3;

/// Most points a polyhedron contact carries: every vertex of the clip of two quadrilateral faces
/// (pinacoid faces have 3 or 4 vertices). Larger polygons are reduced to 4 (see point 4 above).
inline constexpr int kMaxPolyhedronContactPoints = 8;

struct PolyhedronContact {
  double gap = 0.0;             ///< signed distance between the surfaces along normal (< 0: penetration depth) [d_L]
  Vec3 normal = Vec3::UnitZ();  ///< unit, from a towards b (for a wall: into the wall)
  ContactType type = ContactType::Simple;
  Feature featureA{};             ///< feature of a in contact (stable key for a contact cache)
  Feature featureB{};             ///< feature of b (for a wall or a sphere: kind Face/Vertex, index 0)
  /// World points on the contact plane, midway between the surfaces. Inline storage: a contact
  /// costs no heap allocation (the nscd narrow phase builds one per pair and step).
  SmallVector<Vec3, kMaxPolyhedronContactPoints> points;
  SmallVector<double, kMaxPolyhedronContactPoints> pointGaps;  ///< gap along normal at each point [d_L]
};

/// Contact between two placed polyhedra, or nullopt if their distance exceeds alert [d_L].
/// angleTol [rad]: tolerance for a face/edge to count as lying in the contact plane.
std::optional<PolyhedronContact> collidePolyhedra(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double alert,
                                                  double angleTol = kFeatureAngleTol);

/// Contact between a placed polyhedron a and a sphere (b), or nullopt if the gap exceeds alert.
/// Exact: the closest point of the polyhedron to the centre (if the centre is inside, the nearest
/// face plane). Always Simple, one point midway between the surfaces; featureA is the closest
/// feature of a, featureB = {Vertex, 0}.
std::optional<PolyhedronContact> collidePolyhedronSphere(const PlacedPolyhedron& a, const Vec3& centre, double radius,
                                                         double alert, double angleTol = kFeatureAngleTol);

/// Contact between a placed polyhedron a and a flat wall {x : inwardNormal.(x - planePoint) >= 0}
/// (b), or nullopt if the lowest vertex is farther than alert. normal = -inwardNormal.
/// Points: every vertex within alert of the plane, projected halfway to the plane (reduced to 4,
/// the deepest and the 3 of largest area with it, only if more than kMaxPolyhedronContactPoints),
/// with their own gaps. The type is the geometric one
/// (classifyPlaneContact, angle tolerance), not the point count: a slightly tilted face gives
/// several predictive points but stays a Simple contact until it lies flat within angleTol.
/// featureA: the support feature of a; featureB = {Face, 0}.
std::optional<PolyhedronContact> collidePolyhedronPlane(const PlacedPolyhedron& a, const Vec3& planePoint,
                                                        const Vec3& inwardNormal, double alert,
                                                        double angleTol = kFeatureAngleTol);

/// Support feature of a body along direction dir (unit, world): vertices within
/// sin(angleTol) * 2R of the support plane; 1 -> Vertex, 2 -> Edge, >= 3 -> Face (the face whose
/// normal is closest to dir).
Feature supportFeature(const PlacedPolyhedron& p, const Vec3& dir, double angleTol = kFeatureAngleTol);

/// Geometric contact type of two touching polyhedra (docs/model.md, "Coordination number"), from
/// their poses only: the normal is recomputed by the narrow phase above, so the answer does not
/// depend on which backend produced the contact nor on the number of points it used. Works for any
/// gap (no alert).
ContactType classifyContact(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double angleTol = kFeatureAngleTol);

/// Same, with an imposed unit normal (from a towards b), e.g. a backend's normal.
ContactType classifyContact(const PlacedPolyhedron& a, const PlacedPolyhedron& b, const Vec3& normal,
                            double angleTol = kFeatureAngleTol);

/// Type of a polyhedron-wall contact from the support feature of a along -inwardNormal:
/// Vertex -> Simple, Edge -> Double, Face -> Triple.
ContactType classifyPlaneContact(const PlacedPolyhedron& a, const Vec3& inwardNormal,
                                 double angleTol = kFeatureAngleTol);

}  // namespace confpack::collision
