#include "collision/polyhedron_contact.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>

namespace confpack::collision {

std::vector<Vec3> PlacedPolyhedron::worldVertices() const {
  std::vector<Vec3> out;
  out.reserve(shape->vertices().size());
  for (const Vec3& v : shape->vertices()) out.push_back(toWorld(v));
  return out;
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Lengths below kRelativeLengthTol x (size of the pair) are zero: a contact region thinner than
// that is a segment, shorter than that a point. Far above rounding (1e-16), far below any physical
// length of the problem (the alert distance is ~1e-3 to 1e-2 d).
constexpr double kRelativeLengthTol = 1e-9;
// Edge pairs whose cross product is shorter than this (relative, i.e. sin of their angle) give no
// separating axis: the face axes already cover parallel edges.
constexpr double kParallelEdgeSin = 1e-9;

// Inline capacities of the per-call arrays below (SmallVector): a pinacoid has 8 vertices,
// 8 faces of at most 4 vertices and 14 edges, so no call allocates; a larger shape spills to the
// heap and still works.
constexpr std::size_t kInlineVertices = 16;  // vertices, faces, polygon vertices
constexpr std::size_t kInlineEdges = 32;

template <class T>
using VertexArray = SmallVector<T, kInlineVertices>;
using Vec2 = Eigen::Vector2d;
using Polygon2 = VertexArray<Vec2>;

// A polyhedron in world coordinates with the topology the narrow phase needs.
struct WorldPoly {
  const ConvexPolyhedron* shape = nullptr;
  VertexArray<Vec3> v;                                          // world vertices
  VertexArray<Vec3> n;                                          // world outward face normals
  VertexArray<double> off;                                      // n.x = off on the face
  SmallVector<std::array<int, 2>, kInlineEdges> edgeFaces;      // the two faces adjacent to each edge
  SmallVector<Vec3, kInlineEdges> edgeArc;                      // n[face1] x n[face0]: the edge's Gauss-map arc normal
  Vec3 centre = Vec3::Zero();                 // an interior point (vertex mean)
  double radius = 0.0;                        // bounding radius of the shape

  explicit WorldPoly(const PlacedPolyhedron& p, bool withTopology = true) : shape(p.shape) {
    if (shape == nullptr) throw std::invalid_argument("PlacedPolyhedron.shape is null");
    for (const Vec3& x : shape->vertices()) {
      v.push_back(p.toWorld(x));
      centre += v.back();
    }
    centre /= static_cast<double>(v.size());
    radius = shape->boundingRadius();
    const auto& bn = shape->faceNormals();
    for (std::size_t f = 0; f < bn.size(); ++f) {
      n.push_back(p.rotation * bn[f]);
      // The body offset is n_b.x_b; in world n_w.(R x_b + t) = n_b.x_b + n_w.t.
      off.push_back(shape->faceOffsets()[f] + n.back().dot(p.position));
    }
    if (withTopology) {
      // Edge -> adjacent faces through a vertex-pair table (the edge list is sorted by (lo, hi)).
      const auto& edges = shape->edges();
      const int nv = static_cast<int>(v.size());
      thread_local std::vector<int> pairToEdge;
      pairToEdge.assign(static_cast<std::size_t>(nv) * nv, -1);
      for (std::size_t e = 0; e < edges.size(); ++e) pairToEdge[edges[e][0] * nv + edges[e][1]] = static_cast<int>(e);
      edgeFaces.clear();
      for (std::size_t e = 0; e < edges.size(); ++e) edgeFaces.push_back({-1, -1});
      for (std::size_t f = 0; f < shape->faces().size(); ++f) {
        const auto& loop = shape->faces()[f];
        for (std::size_t k = 0; k < loop.size(); ++k) {
          const int i = loop[k], j = loop[(k + 1) % loop.size()];
          const int e = pairToEdge[std::min(i, j) * nv + std::max(i, j)];
          if (e >= 0) edgeFaces[e][edgeFaces[e][0] < 0 ? 0 : 1] = static_cast<int>(f);
        }
      }
      for (const auto& ef : edgeFaces) edgeArc.push_back(n[ef[1]].cross(n[ef[0]]));
    }
  }

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

// Closest points of segments p1-q1 and p2-q2 (Ericson, Real-Time Collision Detection, 5.1.9).
// Returns squared distance; s, t are the parameters on each segment.
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

// True if the projection of x on the plane of face f lies inside the face polygon (closed).
bool projectsInsideFace(const WorldPoly& w, int f, const Vec3& x) {
  const auto& loop = w.shape->faces()[f];
  const Vec3& nf = w.n[f];
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec3& a = w.v[loop[k]];
    const Vec3& b = w.v[loop[(k + 1) % loop.size()]];
    // CCW loop around nf: inside is to the left of every edge.
    if ((b - a).cross(x - a).dot(nf) < 0.0) return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Separating-axis test.

struct SatResult {
  double sep = -kInf;         // largest separation over the axes [d_L]
  Vec3 axis = Vec3::UnitZ();  // from a towards b
};

// Gauss-map test (Gregorius, "The Separating Axis Test between Convex Polyhedra", GDC 2013):
// edges of A (adjacent face normals a, b) and of B (c, d) build a face of the Minkowski
// difference A - B iff the arcs a-b and (-c)-(-d) cross on the unit sphere. Only those edge
// pairs can carry the minimum-penetration axis, and for them the supports along the axis are
// the edges themselves, so sep costs one dot product. With the arc normals b x a and d x c
// precomputed per edge, the test is 4 dot products:
//   c.(b x a) * d.(b x a) < 0,  a.(d x c) * b.(d x c) < 0,  c.(b x a) * b.(d x c) > 0.

// Returns the best axis; stops early (with sep > stopAbove) once an axis proves separation
// beyond stopAbove.
SatResult separatingAxis(const WorldPoly& A, const WorldPoly& B, double stopAbove) {
  SatResult best;
  const double tieTol = kRelativeLengthTol * (A.radius + B.radius);
  for (std::size_t f = 0; f < A.n.size(); ++f) {
    const double s = B.minAlong(A.n[f]) - A.off[f];
    if (s > best.sep) best = {s, A.n[f]};
    if (s > stopAbove) return best;
  }
  for (std::size_t f = 0; f < B.n.size(); ++f) {
    const double s = A.minAlong(B.n[f]) - B.off[f];
    // Face of B: axis from a towards b is -n_B. Ties keep A's face (deterministic).
    if (s > best.sep + tieTol) best = {s, -B.n[f]};
    if (s > stopAbove) return best;
  }
  const auto& eA = A.shape->edges();
  const auto& eB = B.shape->edges();
  for (std::size_t i = 0; i < eA.size(); ++i) {
    const Vec3& pa = A.v[eA[i][0]];
    const Vec3 da = A.v[eA[i][1]] - pa;
    const Vec3& na0 = A.n[A.edgeFaces[i][0]];
    const Vec3& na1 = A.n[A.edgeFaces[i][1]];
    const Vec3& bxa = A.edgeArc[i];
    for (std::size_t j = 0; j < eB.size(); ++j) {
      // isMinkowskiFace(na0, na1, -nb0, -nb1) with the arc normals precomputed:
      // (-nb1) x (-nb0) = nb1 x nb0 = B.edgeArc[j].
      const Vec3& nb0 = B.n[B.edgeFaces[j][0]];
      const Vec3& nb1 = B.n[B.edgeFaces[j][1]];
      const Vec3& dxc = B.edgeArc[j];
      const double cba = -nb0.dot(bxa), dba = -nb1.dot(bxa), adc = na0.dot(dxc), bdc = na1.dot(dxc);
      if (!(cba * dba < 0.0 && adc * bdc < 0.0 && cba * bdc > 0.0)) continue;
      const Vec3& pb = B.v[eB[j][0]];
      const Vec3 db = B.v[eB[j][1]] - pb;
      Vec3 u = da.cross(db);
      const double len = u.norm();
      if (len <= kParallelEdgeSin * da.norm() * db.norm()) continue;
      u /= len;
      if (u.dot(pa - A.centre) < 0.0) u = -u;  // outward from A at its edge
      const double s = u.dot(pb - pa);
      // Edge axes must beat the face axes clearly: an edge pair lying in a face gives the face
      // normal again, and the face reading is the one that classifies the contact correctly.
      if (s > best.sep + tieTol) best = {s, u};
      if (s > stopAbove) return best;
    }
  }
  return best;
}

// Exact distance of two disjoint convex polyhedra: the closest pair is vertex-face (the vertex
// projecting inside the face) or edge-edge (which includes vertex-edge and vertex-vertex).
// Returns the distance and the unit direction from A to B; face-based pairs return the exact
// face normal (preferred on ties, so parallel faces give the face normal, not a rounded one).
struct DistanceResult {
  double distance = kInf;
  Vec3 normal = Vec3::UnitZ();
};

DistanceResult exactDistance(const WorldPoly& A, const WorldPoly& B, const SatResult& sat) {
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

// ---------------------------------------------------------------------------------------------
// Contact features and region.

struct SupportSet {
  VertexArray<int> verts;  // indices within eps of the support plane
  Feature feature{};
};

// Support feature of w along dir (unit): vertices with dir.x >= max - eps.
SupportSet supportSet(const WorldPoly& w, const Vec3& dir, double eps) {
  SupportSet s;
  const double h = w.maxAlong(dir);
  for (int i = 0; i < static_cast<int>(w.v.size()); ++i)
    if (dir.dot(w.v[i]) >= h - eps) s.verts.push_back(i);
  if (s.verts.size() == 1) {
    s.feature = {FeatureKind::Vertex, s.verts[0]};
  } else if (s.verts.size() == 2) {
    s.feature = {FeatureKind::Edge, w.edgeIndex(s.verts[0], s.verts[1])};
  } else {
    int best = 0;
    for (int f = 1; f < static_cast<int>(w.n.size()); ++f)
      if (w.n[f].dot(dir) > w.n[best].dot(dir)) best = f;
    s.feature = {FeatureKind::Face, best};
  }
  return s;
}

double cross2(const Vec2& a, const Vec2& b) {
  return a.x() * b.y() - a.y() * b.x();
}

double polygonArea(std::span<const Vec2> p) {
  double a = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) a += cross2(p[i], p[(i + 1) % p.size()]);
  return 0.5 * a;
}

// Sutherland-Hodgman: subject polygon clipped by a convex CCW clip polygon.
Polygon2 clipPolygon(Polygon2 subject, std::span<const Vec2> clipper) {
  Polygon2 out;
  for (std::size_t k = 0; k < clipper.size() && !subject.empty(); ++k) {
    const Vec2& a = clipper[k];
    const Vec2 e = clipper[(k + 1) % clipper.size()] - a;
    out.clear();
    for (std::size_t i = 0; i < subject.size(); ++i) {
      const Vec2& p = subject[i];
      const Vec2& q = subject[(i + 1) % subject.size()];
      const double dp = cross2(e, p - a), dq = cross2(e, q - a);  // >= 0 inside
      if (dp >= 0.0) out.push_back(p);
      if ((dp >= 0.0) != (dq >= 0.0)) out.push_back(p + dp / (dp - dq) * (q - p));
    }
    std::swap(subject, out);
  }
  return subject;
}

// Clips segment p-q to the convex CCW polygon (Cyrus-Beck). Returns false if nothing is left.
bool clipSegment(Vec2& p, Vec2& q, std::span<const Vec2> poly) {
  double t0 = 0.0, t1 = 1.0;
  const Vec2 d = q - p;
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const Vec2& a = poly[k];
    const Vec2 e = poly[(k + 1) % poly.size()] - a;
    const double num = cross2(e, p - a);  // >= 0 inside at t = 0
    const double den = cross2(e, d);
    if (std::abs(den) < 1e-300) {
      if (num < 0.0) return false;
      continue;
    }
    const double t = -num / den;
    if (den > 0.0)
      t0 = std::max(t0, t);
    else
      t1 = std::min(t1, t);
    if (t0 > t1) return false;
  }
  const Vec2 p0 = p;
  p = p0 + t0 * d;
  q = p0 + t1 * d;
  return true;
}

// Area of the convex hull of 4 points. In convex position one of the 3 cyclic orders is the
// convex quadrilateral and has the largest |shoelace| area (the other two self-intersect); with
// one point inside the triangle of the others, the largest triangle is the hull.
double hullArea4(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  auto quad = [](const Vec2& p, const Vec2& q, const Vec2& r, const Vec2& t) {
    return 0.5 * std::abs(cross2(p, q) + cross2(q, r) + cross2(r, t) + cross2(t, p));
  };
  auto tri = [](const Vec2& p, const Vec2& q, const Vec2& r) { return 0.5 * std::abs(cross2(q - p, r - p)); };
  return std::max(
      {quad(a, b, c, d), quad(a, b, d, c), quad(a, c, b, d), tri(a, b, c), tri(a, b, d), tri(a, c, d), tri(b, c, d)});
}

// Indices of 4 of n > 4 points (a contact polygon's vertices) keeping the deepest one (smallest
// gap) and, with it, the 3 others of largest supported area (convex hull area). Only for
// polygons larger than kMaxPolyhedronContactPoints (never for pinacoids, see keptPoints).
SmallVector<int, 4> pickFour(std::span<const Vec2> pts, std::span<const double> gaps) {
  const int n = static_cast<int>(pts.size());
  const int deep = static_cast<int>(std::min_element(gaps.begin(), gaps.end()) - gaps.begin());
  double best = -1.0;
  SmallVector<int, 4> pick{0, 1, 2, 3};
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k) {
        if (i == deep || j == deep || k == deep) continue;
        const double a = hullArea4(pts[deep], pts[i], pts[j], pts[k]);
        if (a > best) {
          best = a;
          pick = {deep, i, j, k};
        }
      }
  std::sort(pick.begin(), pick.end());  // keep the polygon order of the input
  return pick;
}

// Indices of the contact points kept from a region's candidates: all of them up to
// kMaxPolyhedronContactPoints (header, point 4: a dropped vertex can sink unseen), else 4.
SmallVector<int, kMaxPolyhedronContactPoints> keptPoints(std::span<const Vec2> pts, std::span<const double> gaps) {
  SmallVector<int, kMaxPolyhedronContactPoints> kept;
  if (pts.size() <= static_cast<std::size_t>(kMaxPolyhedronContactPoints)) {
    for (std::size_t i = 0; i < pts.size(); ++i) kept.push_back(static_cast<int>(i));
    return kept;
  }
  for (int i : pickFour(pts, gaps)) kept.push_back(i);
  return kept;
}

// Height (coordinate along n) of a body's contact feature above the lateral point x.
struct FeatureSurface {
  FeatureKind kind = FeatureKind::Vertex;
  Vec3 p0 = Vec3::Zero(), p1 = Vec3::Zero();  // vertex, or edge ends
  Vec3 faceN = Vec3::UnitZ();
  double faceOff = 0.0;
};

struct Frame {
  Vec3 n, u, v;  // n = u x v
  Vec2 lateral(const Vec3& x) const { return {u.dot(x), v.dot(x)}; }
  Vec3 world(const Vec2& x, double h) const { return x.x() * u + x.y() * v + h * n; }
};

double heightAt(const FeatureSurface& s, const Frame& fr, const Vec2& x) {
  switch (s.kind) {
    case FeatureKind::Vertex:
      return fr.n.dot(s.p0);
    case FeatureKind::Edge: {
      const Vec2 a = fr.lateral(s.p0), b = fr.lateral(s.p1);
      const Vec2 d = b - a;
      const double dd = d.squaredNorm();
      const double t = dd > 1e-300 ? std::clamp((x - a).dot(d) / dd, 0.0, 1.0) : 0.0;
      return fr.n.dot(s.p0 + t * (s.p1 - s.p0));
    }
    case FeatureKind::Face: {
      // On the face plane: faceN.(u x_u + v x_v + h n) = faceOff.
      const double dn = s.faceN.dot(fr.n);
      const Vec3 lat = fr.world(x, 0.0);
      if (std::abs(dn) < 1e-12) return fr.n.dot(lat);
      return (s.faceOff - s.faceN.dot(lat)) / dn;
    }
  }
  return 0.0;
}

struct Region {
  ContactType type = ContactType::Simple;
  Polygon2 points;
  // Set when the surface points are known exactly in 3D (crossing edges: the closest points of
  // the two segments); then they are used instead of the lateral points and heights.
  bool exactPair = false;
  SmallVector<std::pair<Vec3, Vec3>, 4> pairs;  // (on A, on B) per point when exactPair
};

// The two support features, each as a surface (for heights) and as its outline projected on the
// contact plane (a point, a segment, or a face polygon counter-clockwise in (u, v)), with what
// every step of contactRegion needs.
struct FeaturePair {
  const WorldPoly& A;
  const SupportSet& sa;
  const WorldPoly& B;
  const SupportSet& sb;
  const Frame& fr;
  double lenTol;  // lengths below this are zero (kRelativeLengthTol x the pair's size)
  Polygon2 pa, pb;
};

// Surface and projected outline of support feature s of w. A's face (normal ~ +n) is CCW in
// (u, v); B's face (normal ~ -n) is CW, so it is reversed (ccwAlongN = false).
void projectFeature(const WorldPoly& w, const SupportSet& s, const Frame& fr, bool ccwAlongN, FeatureSurface& out,
                    Polygon2& poly) {
  out.kind = s.feature.kind;
  if (s.feature.kind == FeatureKind::Vertex) {
    out.p0 = w.v[s.verts[0]];
    poly = {fr.lateral(out.p0)};
  } else if (s.feature.kind == FeatureKind::Edge) {
    out.p0 = w.v[s.verts[0]];
    out.p1 = w.v[s.verts[1]];
    poly = {fr.lateral(out.p0), fr.lateral(out.p1)};
  } else {
    const int f = s.feature.index;
    out.faceN = w.n[f];
    out.faceOff = w.off[f];
    poly.clear();
    for (int i : w.shape->faces()[f]) poly.push_back(fr.lateral(w.v[i]));
    if (!ccwAlongN) std::reverse(poly.begin(), poly.end());
  }
}

// A degenerate region reduced to its two most distant points (a segment, Double) or, if they
// are closer than lenTol, to their midpoint (Simple).
void segmentOrPoint(const Polygon2& pts, double lenTol, Region& r) {
  if (pts.empty()) return;
  std::size_t bi = 0, bj = 0;
  double best = -1.0;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t j = i; j < pts.size(); ++j)
      if ((pts[i] - pts[j]).squaredNorm() > best) {
        best = (pts[i] - pts[j]).squaredNorm();
        bi = i;
        bj = j;
      }
  if (std::sqrt(best) > lenTol) {
    r.type = ContactType::Double;
    r.points = {pts[bi], pts[bj]};
  } else {
    r.type = ContactType::Simple;
    r.points = {0.5 * (pts[bi] + pts[bj])};
  }
}

// Fallback for a single-point contact whose lateral construction does not fall on both
// features (vertex-vertex, vertex-edge, or projections that miss each other, which a large
// angular tolerance allows): the closest pair of points of the two 3D features, found over
// their boundary segments and over vertices projecting inside a face.
Region closestFeaturePair(const FeaturePair& fp) {
  auto loopOf = [](const WorldPoly& w, const SupportSet& s) {
    VertexArray<Vec3> loop;
    if (s.feature.kind == FeatureKind::Face)
      for (int i : w.shape->faces()[s.feature.index]) loop.push_back(w.v[i]);
    else
      for (int i : s.verts) loop.push_back(w.v[i]);
    return loop;
  };
  const VertexArray<Vec3> la = loopOf(fp.A, fp.sa), lb = loopOf(fp.B, fp.sb);
  auto segCount = [](const VertexArray<Vec3>& l) { return l.size() <= 2 ? std::size_t{1} : l.size(); };
  double best = kInf;
  std::pair<Vec3, Vec3> pair{la[0], lb[0]};
  for (std::size_t i = 0; i < segCount(la); ++i)
    for (std::size_t j = 0; j < segCount(lb); ++j) {
      double s, t;
      Vec3 c1, c2;
      const double d2 =
          closestSegmentSegment(la[i], la[(i + 1) % la.size()], lb[j], lb[(j + 1) % lb.size()], s, t, c1, c2);
      if (d2 < best) {
        best = d2;
        pair = {c1, c2};
      }
    }
  auto facePoints = [&](const WorldPoly& w, const SupportSet& s, const VertexArray<Vec3>& other, bool faceIsA) {
    if (s.feature.kind != FeatureKind::Face) return;
    const int f = s.feature.index;
    for (const Vec3& x : other) {
      if (!projectsInsideFace(w, f, x)) continue;
      const Vec3 proj = x - (w.n[f].dot(x) - w.off[f]) * w.n[f];
      const double d2 = (x - proj).squaredNorm();
      if (d2 < best) {
        best = d2;
        pair = faceIsA ? std::make_pair(proj, x) : std::make_pair(x, proj);
      }
    }
  };
  facePoints(fp.A, fp.sa, lb, true);
  facePoints(fp.B, fp.sb, la, false);
  Region r;
  r.type = ContactType::Simple;
  r.points = {0.5 * (fp.fr.lateral(pair.first) + fp.fr.lateral(pair.second))};
  r.exactPair = true;
  r.pairs = {pair};
  return r;
}

// True if x lies in the convex CCW polygon, allowing lenTol outside each edge.
bool insideConvex(const Vec2& x, const Polygon2& poly, double lenTol) {
  for (std::size_t k = 0; k < poly.size(); ++k) {
    const Vec2 e = poly[(k + 1) % poly.size()] - poly[k];
    if (cross2(e, x - poly[k]) < -lenTol * e.norm()) return false;
  }
  return true;
}

// Edge against edge: crossing edges touch in one point, where the closest points of the 3D
// segments project; parallel edges along a segment, the overlap of their projections on A's edge
// line (a line contact), with the surface points at the same abscissa on each 3D edge.
Region edgeEdgeRegion(const FeaturePair& fp, const FeatureSurface& surfA, const FeatureSurface& surfB) {
  Region r;
  const Polygon2 &pa = fp.pa, &pb = fp.pb;
  const Vec2 da = pa[1] - pa[0], db = pb[1] - pb[0];
  const double sinAngle = std::abs(cross2(da, db)) / std::max(da.norm() * db.norm(), 1e-300);
  if (sinAngle > kParallelEdgeSin * 1e3) {
    double s, t;
    Vec3 c1, c2;
    closestSegmentSegment(surfA.p0, surfA.p1, surfB.p0, surfB.p1, s, t, c1, c2);
    r.points = {0.5 * (fp.fr.lateral(c1) + fp.fr.lateral(c2))};
    r.exactPair = true;
    r.pairs = {{c1, c2}};
    return r;
  }
  const Vec2 dir = da.normalized();
  const double a0 = 0.0, a1 = da.norm();
  const double b0 = dir.dot(pb[0] - pa[0]), b1 = dir.dot(pb[1] - pa[0]);
  const double lo = std::max(a0, std::min(b0, b1)), hi = std::min(a1, std::max(b0, b1));
  // The two lines may be offset laterally by rounding or tilt: put points midway across.
  if (hi >= lo)
    segmentOrPoint(Polygon2{pa[0] + lo * dir, pa[0] + hi * dir}, fp.lenTol, r);
  else
    r.points = {pa[0] + 0.5 * (lo + hi) * dir};
  // Surface points: the same abscissa along the common direction on each 3D edge (the lateral
  // lines may be offset by the tilt allowed by the tolerance).
  r.exactPair = true;
  for (const Vec2& x : r.points) {
    const double lam = dir.dot(x - pa[0]);
    const double ta = std::clamp(lam / a1, 0.0, 1.0);
    const double tb = std::abs(b1 - b0) > 1e-300 ? std::clamp((lam - b0) / (b1 - b0), 0.0, 1.0) : 0.0;
    r.pairs.emplace_back(surfA.p0 + ta * (surfA.p1 - surfA.p0), surfB.p0 + tb * (surfB.p1 - surfB.p0));
  }
  return r;
}

// Edge against face: the edge's projection clipped to the face's (a segment or a point), or the
// closest feature pair if it misses the face.
Region edgeFaceRegion(const FeaturePair& fp) {
  const bool edgeIsA = fp.sa.feature.kind == FeatureKind::Edge;
  const Polygon2& seg = edgeIsA ? fp.pa : fp.pb;
  const Polygon2& face = edgeIsA ? fp.pb : fp.pa;
  Vec2 p = seg[0], q = seg[1];
  if (!clipSegment(p, q, face)) return closestFeaturePair(fp);
  Region r;
  segmentOrPoint(Polygon2{p, q}, fp.lenTol, r);
  return r;
}

// Face against face: the intersection of the two projected faces. A polygon of non-negligible
// area is a Triple contact (its vertices kept whole up to 8 in buildContact, keptPoints); a
// sliver is a segment or a point; no overlap falls back to the closest feature pair.
Region faceFaceRegion(const FeaturePair& fp) {
  const Polygon2 poly = clipPolygon(fp.pa, fp.pb);
  if (poly.size() >= 3 && std::abs(polygonArea(poly)) > fp.lenTol * (fp.A.radius + fp.B.radius)) {
    Region r;
    r.type = ContactType::Triple;
    r.points = poly;
    return r;
  }
  if (poly.empty()) return closestFeaturePair(fp);
  Region r;
  segmentOrPoint(poly, fp.lenTol, r);
  return r;
}

// The contact region of feature sets sa (of A, near max along n) and sb (of B, near min along n)
// projected on the contact plane; its dimension gives the contact type. One step per pair of
// feature kinds; surfA and surfB receive the features' surfaces for the heights of the points.
Region contactRegion(const WorldPoly& A, const SupportSet& sa, const WorldPoly& B, const SupportSet& sb,
                     const Frame& fr, FeatureSurface& surfA, FeatureSurface& surfB) {
  FeaturePair fp{A, sa, B, sb, fr, kRelativeLengthTol * (A.radius + B.radius), {}, {}};
  projectFeature(A, sa, fr, true, surfA, fp.pa);
  projectFeature(B, sb, fr, false, surfB, fp.pb);
  const FeatureKind ka = sa.feature.kind, kb = sb.feature.kind;
  if (ka == FeatureKind::Vertex && kb == FeatureKind::Face && insideConvex(fp.pa[0], fp.pb, fp.lenTol)) {
    Region r;  // the vertex over the face
    r.points = {fp.pa[0]};
    return r;
  }
  if (kb == FeatureKind::Vertex && ka == FeatureKind::Face && insideConvex(fp.pb[0], fp.pa, fp.lenTol)) {
    Region r;
    r.points = {fp.pb[0]};
    return r;
  }
  if (ka == FeatureKind::Vertex || kb == FeatureKind::Vertex) return closestFeaturePair(fp);
  if (ka == FeatureKind::Edge && kb == FeatureKind::Edge) return edgeEdgeRegion(fp, surfA, surfB);
  if (ka == FeatureKind::Edge || kb == FeatureKind::Edge) return edgeFaceRegion(fp);
  return faceFaceRegion(fp);
}

Frame frameFor(const Vec3& n) {
  Frame fr;
  fr.n = n;
  fr.u = n.unitOrthogonal();
  fr.v = n.cross(fr.u);
  return fr;
}

// Features, region, type and points of a pair for a given normal (a -> b).
PolyhedronContact buildContact(const WorldPoly& A, const WorldPoly& B, const Vec3& normal, double gap,
                               double angleTol) {
  PolyhedronContact c;
  c.normal = normal;
  c.gap = gap;
  const SupportSet sa = supportSet(A, normal, A.featureEps(angleTol));
  const SupportSet sb = supportSet(B, -normal, B.featureEps(angleTol));
  c.featureA = sa.feature;
  c.featureB = sb.feature;
  const Frame fr = frameFor(normal);
  FeatureSurface surfA, surfB;
  const Region region = contactRegion(A, sa, B, sb, fr, surfA, surfB);
  c.type = region.type;
  if (region.exactPair) {
    for (const auto& [onA, onB] : region.pairs) {
      c.points.push_back(0.5 * (onA + onB));
      c.pointGaps.push_back(normal.dot(onB - onA));
    }
    return c;
  }
  VertexArray<Vec3> points;
  VertexArray<double> gaps;
  for (const Vec2& x : region.points) {
    const double ha = heightAt(surfA, fr, x), hb = heightAt(surfB, fr, x);
    points.push_back(fr.world(x, 0.5 * (ha + hb)));
    gaps.push_back(hb - ha);
  }
  for (int i : keptPoints(region.points, gaps)) {
    c.points.push_back(points[i]);
    c.pointGaps.push_back(gaps[i]);
  }
  return c;
}

// Normal and gap of a pair: SAT for overlap, exact closest features when disjoint.
// Returns false if the distance certainly exceeds alert.
bool pairNormal(const WorldPoly& A, const WorldPoly& B, double alert, Vec3& normal, double& gap) {
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

void checkAlert(double alert, const char* who) {
  if (!(alert >= 0.0)) throw std::invalid_argument(fmt::format("{}: alert must be >= 0 (got {})", who, alert));
}

Vec3 unitOrThrow(const Vec3& n, const char* who) {
  const double len = n.norm();
  if (!(len > 0.0) || !std::isfinite(len))
    throw std::invalid_argument(fmt::format("{}: normal must be a non-zero finite vector", who));
  return n / len;
}

}  // namespace

std::optional<PolyhedronContact> collidePolyhedra(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double alert,
                                                  double angleTol) {
  checkAlert(alert, "collidePolyhedra");
  if (a.shape == nullptr || b.shape == nullptr)
    throw std::invalid_argument("collidePolyhedra: PlacedPolyhedron.shape is null");
  // Bounding spheres first: most broad-phase pairs end here.
  const double reach = a.shape->boundingRadius() + b.shape->boundingRadius() + alert;
  if ((b.position - a.position).squaredNorm() > reach * reach) return std::nullopt;
  const WorldPoly A(a), B(b);
  Vec3 normal;
  double gap;
  if (!pairNormal(A, B, alert, normal, gap)) return std::nullopt;
  return buildContact(A, B, normal, gap, angleTol);
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
  const WorldPoly A(a, false);

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
  const WorldPoly A(a);
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
  const WorldPoly w(p, false);
  return supportSet(w, unitOrThrow(dir, "supportFeature"), w.featureEps(angleTol)).feature;
}

ContactType classifyContact(const PlacedPolyhedron& a, const PlacedPolyhedron& b, double angleTol) {
  if (a.shape == nullptr || b.shape == nullptr)
    throw std::invalid_argument("classifyContact: PlacedPolyhedron.shape is null");
  const WorldPoly A(a), B(b);
  Vec3 normal = Vec3::UnitZ();
  double gap = 0.0;
  pairNormal(A, B, kInf, normal, gap);
  return buildContact(A, B, normal, gap, angleTol).type;
}

ContactType classifyContact(const PlacedPolyhedron& a, const PlacedPolyhedron& b, const Vec3& normal, double angleTol) {
  if (a.shape == nullptr || b.shape == nullptr)
    throw std::invalid_argument("classifyContact: PlacedPolyhedron.shape is null");
  const WorldPoly A(a), B(b);
  return buildContact(A, B, unitOrThrow(normal, "classifyContact"), 0.0, angleTol).type;
}

ContactType classifyPlaneContact(const PlacedPolyhedron& a, const Vec3& inwardNormal, double angleTol) {
  const Feature f = supportFeature(a, -unitOrThrow(inwardNormal, "classifyPlaneContact"), angleTol);
  return f.kind == FeatureKind::Vertex ? ContactType::Simple
         : f.kind == FeatureKind::Edge ? ContactType::Double
                                       : ContactType::Triple;
}

}  // namespace confpack::collision
