#pragma once
// Exact narrow phase for convex polyhedra (pinacoids) and the shared geometric contact-type
// classifier (docs/model.md, "nscd: Moreau-Jean contact dynamics" and "Coordination number").
//
// Method, polyhedron-polyhedron (collidePolyhedra), one file per step, each stating its equations:
// 1. separating_axis: the largest support separation over face normals and Minkowski-face edge
//    pairs; minus the penetration depth when the bodies overlap, a lower bound of the distance
//    otherwise.
// 2. polyhedron_distance: for disjoint bodies, the exact distance and closest direction over
//    vertex-face and edge-edge feature pairs, pruned by the SAT bound (pairNormal: steps 1 and 2
//    give the normal and the gap, never overestimated).
// 3. contact_region: the support feature of each body along the normal (Vertex, Edge or Face
//    within angleTol), their intersection projected on the contact plane (point, segment, or
//    polygon by Sutherland-Hodgman clipping), whose dimension is the type (Simple, Double,
//    Triple).
// 4. contact_region: the points, midway between the surfaces with the gap at each; a face-face
//    contact keeps every vertex of its polygon (up to kMaxPolyhedronContactPoints).
// world_polyhedron holds the placed body in world coordinates that all steps share.
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
/// (pinacoid faces have 3 or 4 vertices). Larger polygons are reduced to 4 (contact_region.hpp).
inline constexpr int kMaxPolyhedronContactPoints = 8;

struct PolyhedronContact {
  double gap = 0.0;             ///< signed distance between the surfaces along normal (< 0: penetration depth) [d_L]
  Vec3 normal = Vec3::UnitZ();  ///< unit, from a towards b (for a wall: into the wall)
  ContactType type = ContactType::Simple;
  Feature featureA{};  ///< feature of a in contact (stable key for a contact cache)
  Feature featureB{};  ///< feature of b (for a wall or a sphere: kind Face/Vertex, index 0)
  /// World points on the contact plane, midway between the surfaces. Inline storage: a contact
  /// costs no heap allocation (the nscd narrow phase builds one per pair and step).
  SmallVector<Vec3, kMaxPolyhedronContactPoints> points;
  SmallVector<double, kMaxPolyhedronContactPoints> pointGaps;  ///< gap along normal at each point [d_L]
};

/// Contact between two placed polyhedra, or nullopt if their distance exceeds alert [d_L].
/// angleTol [rad]: tolerance for a face/edge to count as lying in the contact plane. pointReach
/// [d_L] > 0: the points are every one that can touch within that distance, each with its gap
/// (contact_region.hpp, "Points within reach"); type and features unchanged. 0: the features'
/// own points (what the analysis reads).
std::optional<PolyhedronContact> collidePolyhedra(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double alert,
                                                  double angleTol = kFeatureAngleTol, double pointReach = 0.0);

struct WorldPolyhedron;
/// The same for two polyhedra already in world coordinates (world_polyhedron.hpp), without the
/// bounding-sphere rejection collidePolyhedra starts with: for a caller that places each body once
/// for all its pairs, and has rejected the distant pairs itself. Same result, bit for bit.
std::optional<PolyhedronContact> collideWorldPolyhedra(const WorldPolyhedron& A, const WorldPolyhedron& B, double alert,
                                                       double angleTol = kFeatureAngleTol, double pointReach = 0.0);

/// The same pair read the way LMGC90's common-plane detection reads it (docs/model.md, "The
/// paper-like contact model"; common_plane.cpp has the equations): a pair with at least 3
/// vertices of each body within `band` x (about half a grain size) of the mid plane is face to
/// face, its points the corners (at most 4) of the intersection of the two vertex sets' projected
/// hulls, all with the one gap of the pair; an empty intersection gives a contact with no points.
/// Any other pair is the exact contact (points within reach `alert`). nullopt beyond alert.
std::optional<PolyhedronContact> collideCommonPlane(const WorldPolyhedron& A, const WorldPolyhedron& B, double alert,
                                                    double band);

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
