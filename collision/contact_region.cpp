#include "collision/contact_region.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "collision/polyhedron_distance.hpp"

namespace confpack::collision {

namespace {

// Faces tilted more than acos(0.1), about 84 degrees, from the contact plane give no points within
// reach (reachFace).
constexpr double kReachFaceMinCos = 0.1;

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

// Height (coordinate along n) of a body's contact feature above the lateral point x.
struct FeatureSurface {
  FeatureKind kind = FeatureKind::Vertex;
  Vec3 p0 = Vec3::Zero(), p1 = Vec3::Zero();  // vertex, or edge ends
  Vec3 faceN = Vec3::UnitZ();
  double faceOff = 0.0;
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
  const WorldPolyhedron& A;
  const SupportSet& sa;
  const WorldPolyhedron& B;
  const SupportSet& sb;
  const Frame& fr;
  double lenTol;  // lengths below this are zero (kRelativeLengthTol x the pair's size)
  Polygon2 pa, pb;
};

// Surface and projected outline of support feature s of w. A's face (normal ~ +n) is CCW in
// (u, v); B's face (normal ~ -n) is CW, so it is reversed (ccwAlongN = false).
void projectFeature(const WorldPolyhedron& w, const SupportSet& s, const Frame& fr, bool ccwAlongN, FeatureSurface& out,
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
  auto loopOf = [](const WorldPolyhedron& w, const SupportSet& s) {
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
  auto facePoints = [&](const WorldPolyhedron& w, const SupportSet& s, const VertexArray<Vec3>& other, bool faceIsA) {
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
Region contactRegion(const WorldPolyhedron& A, const SupportSet& sa, const WorldPolyhedron& B, const SupportSet& sb,
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

// Above lateral point x: the point midway between the two surfaces, and its gap (h_B - h_A).
struct SurfacePoint {
  Vec3 point;
  double gap;
};
SurfacePoint pointAt(const FeatureSurface& surfA, const FeatureSurface& surfB, const Frame& fr, const Vec2& x) {
  const double ha = heightAt(surfA, fr, x), hb = heightAt(surfB, fr, x);
  return {fr.world(x, 0.5 * (ha + hb)), hb - ha};
}

// c's points: those of the candidates (lateral positions, points, gaps) that keptPoints keeps.
void setKeptPoints(std::span<const Vec2> lateral, const VertexArray<Vec3>& points, const VertexArray<double>& gaps,
                   PolyhedronContact& c) {
  c.points.clear();
  c.pointGaps.clear();
  for (int i : keptPoints(lateral, gaps)) {
    c.points.push_back(points[i]);
    c.pointGaps.push_back(gaps[i]);
  }
}

// The face of w through its support vertex along dir (unit) with the most vertices within reach
// of the support plane, ties to the face most aligned with dir: the face whose part near the
// contact plane holds the points that can touch within reach. Faces steeper than about 84
// degrees to the plane are left out (a lateral point's height on them is ill-conditioned); -1 if
// no face is left.
int reachFace(const WorldPolyhedron& w, const Vec3& dir, double reach) {
  int top = 0;
  for (int i = 1; i < static_cast<int>(w.v.size()); ++i)
    if (dir.dot(w.v[i]) > dir.dot(w.v[top])) top = i;
  const double floor = dir.dot(w.v[top]) - reach;
  int best = -1, bestCount = 0;
  double bestAlign = 0.0;
  const auto& faces = w.shape->faces();
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    const double align = w.n[f].dot(dir);
    if (align < kReachFaceMinCos || std::find(faces[f].begin(), faces[f].end(), top) == faces[f].end()) continue;
    const auto count = std::count_if(faces[f].begin(), faces[f].end(), [&](int i) { return dir.dot(w.v[i]) >= floor; });
    if (count > bestCount || (count == bestCount && align > bestAlign)) {
      best = f;
      bestCount = static_cast<int>(count);
      bestAlign = align;
    }
  }
  return best;
}

// Points within reach (contact_region.hpp): the vertices of the overlap of the two reach faces'
// projections, those within `reach` of the deepest, each with the exact gap between the two face
// planes. They replace c's points only if they hold its deepest one: otherwise the two faces do
// not cover the contact (a vertex against an edge beside both faces, say) and c keeps its own.
void pointsWithinReach(const WorldPolyhedron& A, const WorldPolyhedron& B, const Frame& fr, double reach,
                       PolyhedronContact& c) {
  const int fa = reachFace(A, fr.n, reach), fb = reachFace(B, -fr.n, reach);
  if (fa < 0 || fb < 0 || c.pointGaps.empty()) return;
  FeatureSurface surfA, surfB;
  Polygon2 pa, pb;
  projectFeature(A, SupportSet{{}, {FeatureKind::Face, fa}}, fr, true, surfA, pa);
  projectFeature(B, SupportSet{{}, {FeatureKind::Face, fb}}, fr, false, surfB, pb);
  const Polygon2 region = clipPolygon(pa, pb);
  const double deepest = *std::min_element(c.pointGaps.begin(), c.pointGaps.end());
  const double lenTol = kRelativeLengthTol * (A.radius + B.radius);
  VertexArray<Vec3> points;
  VertexArray<double> gaps;
  Polygon2 lateral;
  double reached = kInf;
  for (const Vec2& x : region) {
    const SurfacePoint sp = pointAt(surfA, surfB, fr, x);
    reached = std::min(reached, sp.gap);
    if (sp.gap > deepest + reach) continue;
    // Clipping repeats a vertex that lies on an edge of the clip polygon.
    if (std::any_of(lateral.begin(), lateral.end(), [&](const Vec2& y) { return (x - y).norm() <= lenTol; })) continue;
    lateral.push_back(x);
    points.push_back(sp.point);
    gaps.push_back(sp.gap);
  }
  // The deepest candidate is always kept (its gap is within reach, and a repeat only follows a
  // kept copy), so reaching the deepest point means some points were kept.
  if (reached > deepest + lenTol) return;
  setKeptPoints(lateral, points, gaps, c);
}

}  // namespace

Polygon2 convexHull(Polygon2 pts) {
  std::sort(pts.begin(), pts.end(),
            [](const Vec2& p, const Vec2& q) { return p.x() < q.x() || (p.x() == q.x() && p.y() < q.y()); });
  if (pts.size() == 2 && pts[0] == pts[1]) return {pts[0]};
  if (pts.size() < 3) return pts;
  std::vector<Vec2> hull;
  auto turnsLeft = [&](const Vec2& p) {
    const std::size_t k = hull.size();
    return cross2(hull[k - 1] - hull[k - 2], p - hull[k - 2]) > 0.0;
  };
  for (const Vec2& p : pts) {  // lower chain
    while (hull.size() >= 2 && !turnsLeft(p)) hull.pop_back();
    hull.push_back(p);
  }
  const std::size_t lower = hull.size() + 1;
  for (std::size_t i = pts.size() - 1; i-- > 0;) {  // upper chain
    while (hull.size() >= lower && !turnsLeft(pts[i])) hull.pop_back();
    hull.push_back(pts[i]);
  }
  hull.pop_back();  // the last point repeats the first
  Polygon2 out;
  for (const Vec2& p : hull) out.push_back(p);
  return out;
}

Vec3 unitOrThrow(const Vec3& n, const char* who) {
  const double len = n.norm();
  if (!(len > 0.0) || !std::isfinite(len))
    throw std::invalid_argument(fmt::format("{}: normal must be a non-zero finite vector", who));
  return n / len;
}

Polygon2 touchingProjections(const WorldPolyhedron& w, const Frame& fr, double level, double sign) {
  Polygon2 out;
  for (const Vec3& x : w.v)
    if (sign * fr.n.dot(x) >= sign * level) out.push_back(fr.lateral(x));
  return out;
}

double polygonArea(std::span<const Vec2> p) {
  double a = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) a += cross2(p[i], p[(i + 1) % p.size()]);
  return 0.5 * a;
}

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

SupportSet supportSet(const WorldPolyhedron& w, const Vec3& dir, double eps) {
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

Frame frameFor(const Vec3& n) {
  Frame fr;
  fr.n = n;
  fr.u = n.unitOrthogonal();
  fr.v = n.cross(fr.u);
  return fr;
}

SmallVector<int, kMaxPolyhedronContactPoints> keptPoints(std::span<const Vec2> pts, std::span<const double> gaps) {
  SmallVector<int, kMaxPolyhedronContactPoints> kept;
  if (pts.size() <= static_cast<std::size_t>(kMaxPolyhedronContactPoints)) {
    for (std::size_t i = 0; i < pts.size(); ++i) kept.push_back(static_cast<int>(i));
    return kept;
  }
  for (int i : pickFour(pts, gaps)) kept.push_back(i);
  return kept;
}

PolyhedronContact buildContact(const WorldPolyhedron& A, const WorldPolyhedron& B, const Vec3& normal, double gap,
                               double angleTol, double pointReach) {
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
  } else {
    VertexArray<Vec3> points;
    VertexArray<double> gaps;
    for (const Vec2& x : region.points) {
      const SurfacePoint sp = pointAt(surfA, surfB, fr, x);
      points.push_back(sp.point);
      gaps.push_back(sp.gap);
    }
    setKeptPoints(region.points, points, gaps, c);
  }
  if (pointReach > 0.0) pointsWithinReach(A, B, fr, pointReach, c);
  return c;
}

}  // namespace confpack::collision
