#include "collision/polyhedron_distance.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace confpack::collision {

double closestSegmentSegment(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, double& s, double& t,
                             Vec3& c1, Vec3& c2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double tiny = 1e-300;
  if (a <= tiny && e <= tiny) {
    s = t = 0.0;
  } else if (a <= tiny) {
    s = 0.0;
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= tiny) {
      t = 0.0;
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      s = denom > 1e-30 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  c1 = p1 + s * d1;
  c2 = p2 + t * d2;
  return (c1 - c2).squaredNorm();
}

DistanceResult exactDistance(const WorldPolyhedron& A, const WorldPolyhedron& B, const SatResult& sat) {
  DistanceResult r;
  const double tieTol = kRelativeLengthTol * (A.radius + B.radius);
  // sat.sep is a lower bound of the distance: a candidate reaching it is optimal, and a feature
  // pair whose separation along sat.axis already exceeds the best candidate cannot win.
  const Vec3& u = sat.axis;
  const double optimal = sat.sep + tieTol;
  // Initial upper bound: the distance between the two support vertices along the axis.
  int ia = 0, ib = 0;
  for (int i = 1; i < static_cast<int>(A.v.size()); ++i)
    if (u.dot(A.v[i]) > u.dot(A.v[ia])) ia = i;
  for (int i = 1; i < static_cast<int>(B.v.size()); ++i)
    if (u.dot(B.v[i]) < u.dot(B.v[ib])) ib = i;
  double upper = (B.v[ib] - A.v[ia]).norm();

  for (std::size_t f = 0; f < A.n.size() && r.distance > optimal; ++f)
    for (const Vec3& x : B.v) {
      const double d = A.n[f].dot(x) - A.off[f];
      if (d >= 0.0 && d < r.distance && d <= upper && projectsInsideFace(A, static_cast<int>(f), x)) r = {d, A.n[f]};
    }
  for (std::size_t f = 0; f < B.n.size() && r.distance > optimal; ++f)
    for (const Vec3& x : A.v) {
      const double d = B.n[f].dot(x) - B.off[f];
      if (d >= 0.0 && d < r.distance - tieTol && d <= upper && projectsInsideFace(B, static_cast<int>(f), x))
        r = {d, -B.n[f]};
    }
  if (r.distance <= optimal) return r;
  upper = std::min(upper, r.distance);
  // Heights along the axis, for the edge-pair lower bound.
  thread_local std::vector<double> ha, hb;
  ha.resize(A.v.size());
  hb.resize(B.v.size());
  for (std::size_t i = 0; i < A.v.size(); ++i) ha[i] = u.dot(A.v[i]);
  for (std::size_t i = 0; i < B.v.size(); ++i) hb[i] = u.dot(B.v[i]);
  const auto& eA = A.shape->edges();
  const auto& eB = B.shape->edges();
  for (const auto& ea : eA) {
    const double topA = std::max(ha[ea[0]], ha[ea[1]]);
    for (const auto& eb : eB) {
      // |c2 - c1| >= u.(c2 - c1) >= min over b's ends - max over a's ends.
      if (std::min(hb[eb[0]], hb[eb[1]]) - topA > std::min(upper, r.distance)) continue;
      double s, t;
      Vec3 c1, c2;
      const double d2 = closestSegmentSegment(A.v[ea[0]], A.v[ea[1]], B.v[eb[0]], B.v[eb[1]], s, t, c1, c2);
      const double d = std::sqrt(d2);
      if (d < r.distance - tieTol && d <= 0.0) {
        r = {d, u};  // touching to rounding although SAT saw a positive gap: keep SAT's axis
      } else if (d < r.distance - tieTol) {
        // Two readings of the direction: (c2 - c1)/d, which carries rounding/d and, for nearly
        // parallel edges, the ill-conditioning of where along them the closest points sit; and
        // the edges' cross product, exact for crossing edges. The true closest direction n*
        // is the one of largest support separation (sep(n*) = distance, sep(u) < distance
        // otherwise), so keep whichever separates more.
        const Vec3 da = A.v[ea[1]] - A.v[ea[0]], db = B.v[eb[1]] - B.v[eb[0]];
        r = {d, (c2 - c1) / d};
        Vec3 w = da.cross(db);
        if (w.norm() > kParallelEdgeSin * da.norm() * db.norm()) {
          w.normalize();
          if (w.dot(c2 - c1) < 0.0) w = -w;
          if (B.minAlong(w) - A.maxAlong(w) >= B.minAlong(r.normal) - A.maxAlong(r.normal)) r.normal = w;
        }
      }
    }
  }
  return r;
}

// Normal and gap of a pair: SAT for overlap, exact closest features when disjoint.
// Returns false if the distance certainly exceeds alert.
bool pairNormal(const WorldPolyhedron& A, const WorldPolyhedron& B, double alert, Vec3& normal, double& gap) {
  const SatResult sat = separatingAxis(A, B, alert);
  if (sat.sep > alert) return false;
  if (sat.sep <= 0.0) {
    normal = sat.axis;
    gap = sat.sep;
    return true;
  }
  const DistanceResult d = exactDistance(A, B, sat);
  if (!std::isfinite(d.distance)) {  // cannot happen for disjoint polytopes; be safe anyway
    normal = sat.axis;
    gap = sat.sep;
    return true;
  }
  if (d.distance > alert) return false;
  normal = d.normal;
  gap = d.distance;
  // The closest direction n* is the axis of largest support separation. When the closest pair
  // is nearly degenerate (an edge almost perpendicular to n*, within ~1e-11 of the distance of
  // a neighbouring pair) the closest-point direction can be off by 1e-5 rad while the SAT axis
  // is exact: keep the SAT axis if it separates clearly more. Ties keep the closest-feature
  // normal (face normals for face-based contacts).
  const double sepClosest = B.minAlong(normal) - A.maxAlong(normal);
  if (sat.sep > sepClosest + 1e-13 * (A.radius + B.radius)) normal = sat.axis;
  return true;
}

namespace {
// `a`, once both shapes are known to be set (a WorldPolyhedron reads its shape).
const PlacedPolyhedron& bothShaped(const PlacedPolyhedron& a, const PlacedPolyhedron& b, const char* caller) {
  if (a.shape == nullptr || b.shape == nullptr)
    throw std::invalid_argument(std::string(caller) + ": PlacedPolyhedron.shape is null");
  return a;
}
}  // namespace

PlacedPair::PlacedPair(const PlacedPolyhedron& a, const PlacedPolyhedron& b, const char* caller)
    : A(bothShaped(a, b, caller)), B(b) {
  pairNormal(A, B, kInf, normal, gap);
}

}  // namespace confpack::collision
