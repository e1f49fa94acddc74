#include "collision/polyhedron_contact.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "collision/contact_region.hpp"
#include "collision/polyhedron_distance.hpp"
#include "collision/world_polyhedron.hpp"

namespace confpack::collision {

std::vector<Vec3> PlacedPolyhedron::worldVertices() const {
  std::vector<Vec3> out;
  out.reserve(shape->vertices().size());
  for (const Vec3& v : shape->vertices()) out.push_back(toWorld(v));
  return out;
}

namespace {

void checkAlert(double alert, const char* who) {
  if (!(alert >= 0.0)) throw std::invalid_argument(fmt::format("{}: alert must be >= 0 (got {})", who, alert));
}

}  // namespace

std::optional<PolyhedronContact> collidePolyhedra(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double alert,
                                                  double angleTol, double pointReach) {
  checkAlert(alert, "collidePolyhedra");
  if (a.shape == nullptr || b.shape == nullptr)
    throw std::invalid_argument("collidePolyhedra: PlacedPolyhedron.shape is null");
  // Bounding spheres first: most broad-phase pairs end here.
  const double reach = a.shape->boundingRadius() + b.shape->boundingRadius() + alert;
  if ((b.position - a.position).squaredNorm() > reach * reach) return std::nullopt;
  return collideWorldPolyhedra(WorldPolyhedron(a), WorldPolyhedron(b), alert, angleTol, pointReach);
}

std::optional<PolyhedronContact> collideWorldPolyhedra(const WorldPolyhedron& A, const WorldPolyhedron& B, double alert,
                                                       double angleTol, double pointReach) {
  checkAlert(alert, "collideWorldPolyhedra");
  if (A.shape == nullptr || B.shape == nullptr)
    throw std::invalid_argument("collideWorldPolyhedra: a WorldPolyhedron has no shape");
  Vec3 normal;
  double gap;
  if (!pairNormal(A, B, alert, normal, gap)) return std::nullopt;
  return buildContact(A, B, normal, gap, angleTol, pointReach);
}

std::optional<PolyhedronContact> collidePolyhedronSphere(const PlacedPolyhedron& a, const Vec3& centre, double radius,
                                                         double alert, double angleTol) {
  checkAlert(alert, "collidePolyhedronSphere");
  if (!(radius > 0.0))
    throw std::invalid_argument(fmt::format("collidePolyhedronSphere: radius must be positive (got {})", radius));
  if (a.shape == nullptr) throw std::invalid_argument("collidePolyhedronSphere: PlacedPolyhedron.shape is null");
  const double reach = a.shape->boundingRadius() + radius + alert;
  if ((centre - a.position).squaredNorm() > reach * reach) return std::nullopt;
  (void)angleTol;  // a sphere touches through one point whatever the polyhedron's feature
  const WorldPolyhedron A(a, false);

  PolyhedronContact c;
  c.type = ContactType::Simple;
  c.featureB = {FeatureKind::Vertex, 0};
  // Signed distances of the centre to the face planes; inside iff all <= 0.
  int nearestFace = 0;
  double maxD = -kInf;
  for (std::size_t f = 0; f < A.n.size(); ++f) {
    const double d = A.n[f].dot(centre) - A.off[f];
    if (d > maxD) {
      maxD = d;
      nearestFace = static_cast<int>(f);
    }
  }
  Vec3 closest = centre;
  if (maxD <= 0.0) {
    // Centre inside: the nearest surface point is on the nearest face plane (convexity).
    c.normal = A.n[nearestFace];
    closest = centre - maxD * c.normal;
    c.gap = maxD - radius;
    c.featureA = {FeatureKind::Face, nearestFace};
  } else {
    // Outside: the closest point is the projection on a face (if it falls inside it) or on an edge.
    double best = kInf;
    for (std::size_t f = 0; f < A.n.size(); ++f) {
      const double d = A.n[f].dot(centre) - A.off[f];
      if (d >= 0.0 && d < best && projectsInsideFace(A, static_cast<int>(f), centre)) {
        best = d;
        c.normal = A.n[f];
        closest = centre - d * A.n[f];
        c.featureA = {FeatureKind::Face, static_cast<int>(f)};
      }
    }
    const auto& edges = A.shape->edges();
    const double tieTol = kRelativeLengthTol * A.radius;
    for (std::size_t e = 0; e < edges.size(); ++e) {
      const Vec3& p = A.v[edges[e][0]];
      const Vec3 d = A.v[edges[e][1]] - p;
      const double t = std::clamp((centre - p).dot(d) / d.squaredNorm(), 0.0, 1.0);
      const Vec3 q = p + t * d;
      const double dist = (centre - q).norm();
      if (dist < best - tieTol) {
        best = dist;
        closest = q;
        c.normal = (centre - q) / dist;
        if (t <= 0.0)
          c.featureA = {FeatureKind::Vertex, edges[e][0]};
        else if (t >= 1.0)
          c.featureA = {FeatureKind::Vertex, edges[e][1]};
        else
          c.featureA = {FeatureKind::Edge, static_cast<int>(e)};
      }
    }
    c.gap = best - radius;
  }
  if (c.gap > alert) return std::nullopt;
  // Midway between the polyhedron surface point and the sphere surface point.
  const Vec3 onSphere = centre - radius * c.normal;
  c.points = {0.5 * (closest + onSphere)};
  c.pointGaps = {c.gap};
  return c;
}

std::optional<PolyhedronContact> collidePolyhedronPlane(const PlacedPolyhedron& a, const Vec3& planePoint,
                                                        const Vec3& inwardNormal, double alert, double angleTol) {
  checkAlert(alert, "collidePolyhedronPlane");
  if (a.shape == nullptr) throw std::invalid_argument("collidePolyhedronPlane: PlacedPolyhedron.shape is null");
  const Vec3 m = unitOrThrow(inwardNormal, "collidePolyhedronPlane");
  if (m.dot(a.position - planePoint) - a.shape->boundingRadius() > alert) return std::nullopt;
  const WorldPolyhedron A(a);
  VertexArray<double> h;
  h.resize(A.v.size());
  double gap = kInf;
  for (std::size_t i = 0; i < A.v.size(); ++i) {
    h[i] = m.dot(A.v[i] - planePoint);
    gap = std::min(gap, h[i]);
  }
  if (gap > alert) return std::nullopt;

  PolyhedronContact c;
  c.normal = -m;
  c.gap = gap;
  const SupportSet sa = supportSet(A, c.normal, A.featureEps(angleTol));
  c.featureA = sa.feature;
  c.featureB = {FeatureKind::Face, 0};
  c.type = sa.feature.kind == FeatureKind::Vertex ? ContactType::Simple
           : sa.feature.kind == FeatureKind::Edge ? ContactType::Double
                                                  : ContactType::Triple;
  // Points: every vertex within alert, and every vertex of the support feature (so a Triple
  // contact always has >= 3 points even if the alert is smaller than its tilt).
  const double reachH = std::max(alert, gap + A.featureEps(angleTol));
  const Frame fr = frameFor(c.normal);
  Polygon2 lat;
  VertexArray<int> idx;
  for (std::size_t i = 0; i < A.v.size(); ++i)
    if (h[i] <= reachH) {
      lat.push_back(fr.lateral(A.v[i]));
      idx.push_back(static_cast<int>(i));
    }
  VertexArray<double> latGaps;
  for (int i : idx) latGaps.push_back(h[i]);
  for (int k : keptPoints(lat, latGaps)) {
    const int i = idx[k];
    c.points.push_back(A.v[i] - 0.5 * h[i] * m);
    c.pointGaps.push_back(h[i]);
  }
  return c;
}

Feature supportFeature(const PlacedPolyhedron& p, const Vec3& dir, double angleTol) {
  const WorldPolyhedron w(p, false);
  return supportSet(w, unitOrThrow(dir, "supportFeature"), w.featureEps(angleTol)).feature;
}

ContactType classifyContact(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double angleTol) {
  const PlacedPair pair(a, b, "classifyContact");
  return buildContact(pair.A, pair.B, pair.normal, pair.gap, angleTol).type;
}

ContactType classifyContact(const PlacedPolyhedron& a, const PlacedPolyhedron& b, const Vec3& normal, double angleTol) {
  if (a.shape == nullptr || b.shape == nullptr)
    throw std::invalid_argument("classifyContact: PlacedPolyhedron.shape is null");
  const WorldPolyhedron A(a), B(b);
  return buildContact(A, B, unitOrThrow(normal, "classifyContact"), 0.0, angleTol).type;
}

ContactType classifyPlaneContact(const PlacedPolyhedron& a, const Vec3& inwardNormal, double angleTol) {
  const Feature f = supportFeature(a, -unitOrThrow(inwardNormal, "classifyPlaneContact"), angleTol);
  return f.kind == FeatureKind::Vertex ? ContactType::Simple
         : f.kind == FeatureKind::Edge ? ContactType::Double
                                       : ContactType::Triple;
}

}  // namespace confpack::collision