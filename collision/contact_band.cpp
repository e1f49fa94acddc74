#include "collision/contact_band.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "collision/contact_region.hpp"
#include "collision/polyhedron_distance.hpp"
#include "collision/world_polyhedron.hpp"

namespace confpack::collision {

namespace {

void checkWidth(double width, const char* who) {
  if (!(width > 0.0) || !std::isfinite(width))
    throw std::invalid_argument(fmt::format("{}: band width must be positive and finite (got {})", who, width));
}

double segmentDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

// Whether p lies in hull h (1, 2 or more vertices, counter-clockwise), within tol.
bool insideHull(const Vec2& p, const Polygon2& h, double tol) {
  if (h.size() == 1) return (p - h[0]).norm() <= tol;
  if (h.size() == 2) return segmentDistance(p, h[0], h[1]) <= tol;
  for (std::size_t i = 0; i < h.size(); ++i) {
    const Vec2& a = h[i];
    const Vec2 e = h[(i + 1) % h.size()] - a;
    if (cross2(e, p - a) < -tol * e.norm()) return false;
  }
  return true;
}

// The hull's sides: none for a point, one for a segment, a closed loop otherwise.
std::size_t sideCount(const Polygon2& h) {
  return h.size() < 2 ? 0 : (h.size() == 2 ? 1 : h.size());
}

// The vertices of H_a ∩ H_b: each hull's vertices inside the other and the crossings of their
// sides (the vertices of an intersection of convex sets are of these two kinds).
Polygon2 hullIntersection(const Polygon2& ha, const Polygon2& hb, double tol) {
  Polygon2 out;
  for (const Vec2& p : ha)
    if (insideHull(p, hb, tol)) out.push_back(p);
  for (const Vec2& p : hb)
    if (insideHull(p, ha, tol)) out.push_back(p);
  for (std::size_t i = 0; i < sideCount(ha); ++i) {
    const Vec2& p = ha[i];
    const Vec2 r = ha[(i + 1) % ha.size()] - p;
    for (std::size_t j = 0; j < sideCount(hb); ++j) {
      const Vec2& q = hb[j];
      const Vec2 s = hb[(j + 1) % hb.size()] - q;
      const double denom = cross2(r, s);
      // Parallel sides meet only along a segment, whose ends are vertices inside the other hull.
      if (std::abs(denom) <= kParallelEdgeSin * r.norm() * s.norm()) continue;
      const double t = cross2(q - p, s) / denom, u = cross2(q - p, r) / denom;
      if (t >= 0.0 && t <= 1.0 && u >= 0.0 && u <= 1.0) out.push_back(p + t * r);
    }
  }
  return out;
}

// The type by the number of distinct positions in pts (positions closer than tol are one):
// 0 or 1 -> Simple; 2, or more within tol of one line -> Double; otherwise Triple.
ContactType typeOfPositions(const Polygon2& pts, double tol) {
  // The two farthest positions span the line, if any, that all others lie on.
  double widest = 0.0;
  std::size_t i0 = 0, i1 = 0;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t j = i + 1; j < pts.size(); ++j)
      if ((pts[j] - pts[i]).norm() > widest) {
        widest = (pts[j] - pts[i]).norm();
        i0 = i;
        i1 = j;
      }
  if (widest <= tol) return ContactType::Simple;
  const Vec2 axis = (pts[i1] - pts[i0]) / widest;
  for (const Vec2& p : pts)
    if (std::abs(cross2(axis, p - pts[i0])) > tol) return ContactType::Triple;
  return ContactType::Double;
}

ContactType bandType(const WorldPolyhedron& A, const WorldPolyhedron& B, const Vec3& normal, double width) {
  const double plane = 0.5 * (A.maxAlong(normal) + B.minAlong(normal));
  const Frame fr = frameFor(normal);
  const double tol = kRelativeLengthTol * (A.radius + B.radius);
  const Polygon2 ha = convexHull(touchingProjections(A, fr, plane - width, 1.0));
  const Polygon2 hb = convexHull(touchingProjections(B, fr, plane + width, -1.0));
  return typeOfPositions(hullIntersection(ha, hb, tol), tol);
}

}  // namespace

ContactType classifyContactBand(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double width) {
  checkWidth(width, "classifyContactBand");
  const PlacedPair pair(a, b, "classifyContactBand");
  return bandType(pair.A, pair.B, pair.normal, width);
}

ContactType classifyContactBand(const PlacedPolyhedron& a, const PlacedPolyhedron& b, const Vec3& normal,
                                double width) {
  checkWidth(width, "classifyContactBand");
  if (a.shape == nullptr || b.shape == nullptr)
    throw std::invalid_argument("classifyContactBand: PlacedPolyhedron.shape is null");
  const WorldPolyhedron A(a, false), B(b, false);
  return bandType(A, B, unitOrThrow(normal, "classifyContactBand"), width);
}

ContactType classifyPlaneContactBand(const PlacedPolyhedron& a, const Vec3& planePoint, const Vec3& inwardNormal,
                                     double width) {
  checkWidth(width, "classifyPlaneContactBand");
  if (a.shape == nullptr) throw std::invalid_argument("classifyPlaneContactBand: PlacedPolyhedron.shape is null");
  const Vec3 n = -unitOrThrow(inwardNormal, "classifyPlaneContactBand");  // from the grain into the wall
  const WorldPolyhedron A(a, false);
  const double plane = 0.5 * (A.maxAlong(n) + n.dot(planePoint));
  const Frame fr = frameFor(n);
  return typeOfPositions(convexHull(touchingProjections(A, fr, plane - width, 1.0)), kRelativeLengthTol * A.radius);
}

}  // namespace confpack::collision
