// The common-plane reading of a polyhedron pair (polyhedron_contact.hpp, collideCommonPlane).
//
// With n the pair's normal (A towards B) and g its gap (pairNormal: the separating axis, or the
// exact closest direction), the extreme heights h_A = max_A n.x and h_B = min_B n.x and the mid
// plane n.x = m = (h_A + h_B) / 2:
//   ref   = min(h_A - n.c_A, n.c_B - h_B)          (c: a body's centre; about half a grain size)
//   d     = max(0, g / 2) + band x ref              (the band about the mid plane)
//   kept  = A's vertices with n.x >= m - d, B's with n.x <= m + d.
// With at least 3 kept vertices on each side the contact is face to face: the convex hulls of the
// two kept sets projected on the plane are intersected; the corners of the intersection (at most
// 4: those with the sharpest turns) are the points, on the mid plane, each with the one gap g. An
// empty or degenerate intersection gives no points, and so no contact this step. Any other pair
// keeps the exact points of buildContact, each with its own gap.
#include <algorithm>
#include <cmath>
#include <vector>

#include "collision/contact_region.hpp"
#include "collision/polyhedron_contact.hpp"
#include "collision/polyhedron_distance.hpp"
#include "collision/world_polyhedron.hpp"

namespace confpack::collision {

namespace {

// The points of a common-plane contact at most (LMGC90 keeps 4 corners of the intersection).
constexpr std::size_t kCommonPlanePoints = 4;

// The corners of a convex polygon with the sharpest turns, at most `keep`, in polygon order.
Polygon2 sharpestCorners(const Polygon2& poly, std::size_t keep) {
  if (poly.size() <= keep) return poly;
  VertexArray<double> turn;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2 in = (poly[i] - poly[(i + poly.size() - 1) % poly.size()]).normalized();
    const Vec2 out = (poly[(i + 1) % poly.size()] - poly[i]).normalized();
    turn.push_back(std::atan2(cross2(in, out), in.dot(out)));
  }
  VertexArray<int> order;
  for (std::size_t i = 0; i < poly.size(); ++i) order.push_back(static_cast<int>(i));
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return turn[a] > turn[b]; });
  std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep));
  Polygon2 out;
  for (std::size_t k = 0; k < keep; ++k) out.push_back(poly[order[k]]);
  return out;
}

}  // namespace

std::optional<PolyhedronContact> collideCommonPlane(const WorldPolyhedron& A, const WorldPolyhedron& B, double alert,
                                                    double band) {
  Vec3 n;
  double gap;
  if (!pairNormal(A, B, alert, n, gap)) return std::nullopt;
  const double hA = A.maxAlong(n), hB = B.minAlong(n);
  const double mid = 0.5 * (hA + hB);
  const double ref = std::min(hA - n.dot(A.centre), n.dot(B.centre) - hB);
  const double reach = std::max(0.0, 0.5 * gap) + band * ref;
  const Frame fr = frameFor(n);
  const Polygon2 keptA = touchingProjections(A, fr, mid - reach, 1.0);
  const Polygon2 keptB = touchingProjections(B, fr, mid + reach, -1.0);
  if (keptA.size() < 3 || keptB.size() < 3) return buildContact(A, B, n, gap, kFeatureAngleTol, alert);

  // Face to face: the exact contact's features (the cache's key) without its points within reach,
  // which the common plane's points replace.
  PolyhedronContact c = buildContact(A, B, n, gap, kFeatureAngleTol);
  const Polygon2 hullA = convexHull(keptA), hullB = convexHull(keptB);
  const double lenTol = kRelativeLengthTol * (A.radius + B.radius);
  const Polygon2 region = hullA.size() >= 3 && hullB.size() >= 3 ? clipPolygon(hullA, hullB) : Polygon2{};
  c.type = ContactType::Triple;
  c.points.clear();
  c.pointGaps.clear();
  if (region.size() < 3 || std::abs(polygonArea(region)) <= lenTol * (A.radius + B.radius)) return c;
  for (const Vec2& x : sharpestCorners(region, kCommonPlanePoints)) {
    c.points.push_back(fr.world(x, mid));
    c.pointGaps.push_back(gap);
  }
  return c;
}

}  // namespace confpack::collision
