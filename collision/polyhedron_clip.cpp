#include "collision/polyhedron_clip.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace confpack::collision {

namespace {

// Vertices closer than this to a cutting plane count as on it. Relative to the coordinate
// magnitude: the signed distance n.x - offset carries a rounding error of a few ulps of |x|.
constexpr double kRelativePlaneTol = 1e-12;

}  // namespace

double ConvexPolytope::volume() const {
  if (empty()) return 0.0;
  // Divergence theorem: V = sum over fan triangles (a, b, c) of every face of det(a-r, b-r, c-r)/6
  // for any reference point r; the vertex mean keeps the lever arms short (less cancellation).
  Vec3 r = Vec3::Zero();
  for (const Vec3& v : vertices) r += v;
  r /= static_cast<double>(vertices.size());
  double sixV = 0.0;
  for (int f = 0; f < faceCount(); ++f) {
    const int s = faceStarts[f], e = faceStarts[f + 1];
    const Vec3 a = vertices[faceIndices[s]] - r;
    for (int i = s + 1; i + 1 < e; ++i)
      sixV += a.dot((vertices[faceIndices[i]] - r).cross(vertices[faceIndices[i + 1]] - r));
  }
  return std::max(0.0, sixV / 6.0);
}

std::pair<Vec3, Vec3> ConvexPolytope::bounds() const {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (const Vec3& v : vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return {lo, hi};
}

ConvexPolytope toPolytope(const PlacedPolyhedron& p) {
  if (p.shape == nullptr) throw std::invalid_argument("toPolytope: PlacedPolyhedron.shape is null");
  ConvexPolytope out;
  out.vertices = p.worldVertices();
  out.faceIndices.clear();
  out.faceStarts.assign(1, 0);
  for (const auto& loop : p.shape->faces()) {
    out.faceIndices.insert(out.faceIndices.end(), loop.begin(), loop.end());
    out.faceStarts.push_back(static_cast<int>(out.faceIndices.size()));
  }
  return out;
}

void clip(const ConvexPolytope& in, const Plane& plane, ConvexPolytope& out) {
  if (&in == &out) {  // aliasing: clearing out would destroy in
    const ConvexPolytope copy = in;
    clip(copy, plane, out);
    return;
  }
  out.vertices.clear();
  out.faceIndices.clear();
  out.faceStarts.assign(1, 0);
  if (in.empty()) return;

  const int nv = static_cast<int>(in.vertices.size());
  // Signed distances (scaled by |normal|) and the tolerance band.
  thread_local std::vector<double> dist;
  dist.resize(nv);
  double scale = std::abs(plane.offset);
  bool anyOut = false, anyIn = false;
  for (int i = 0; i < nv; ++i) {
    scale = std::max(scale, std::abs(plane.normal.dot(in.vertices[i])));
  }
  const double tol = kRelativePlaneTol * std::max(scale, 1e-300);
  for (int i = 0; i < nv; ++i) {
    dist[i] = plane.normal.dot(in.vertices[i]) - plane.offset;
    if (dist[i] > tol) anyOut = true;
    if (dist[i] < -tol) anyIn = true;
  }
  if (!anyOut) {  // entirely kept (touching the plane at most)
    out = in;
    return;
  }
  if (!anyIn) return;  // entirely removed (a face lying in the plane has no volume)

  // Genuine cut: no face lies in the plane. Kept input vertices are renumbered; a cut edge
  // (one end strictly out, the other strictly in) gets one new vertex shared by its two faces.
  thread_local std::vector<int> remap;
  remap.assign(nv, -1);
  thread_local std::vector<std::array<int, 3>> cutEdges;  // (lo, hi, new index)
  cutEdges.clear();
  thread_local std::vector<char> onPlane;  // per output vertex: lies on the cut
  onPlane.clear();

  auto keep = [&](int i) {
    if (remap[i] < 0) {
      remap[i] = static_cast<int>(out.vertices.size());
      out.vertices.push_back(in.vertices[i]);
      onPlane.push_back(dist[i] >= -tol ? 1 : 0);
    }
    return remap[i];
  };
  auto cut = [&](int i, int j) {
    const int lo = std::min(i, j), hi = std::max(i, j);
    for (const auto& c : cutEdges)
      if (c[0] == lo && c[1] == hi) return c[2];
    // t from the inside end so that the point is a convex combination (never extrapolates).
    const int a = dist[lo] < 0.0 ? lo : hi, b = a == lo ? hi : lo;
    const double t = dist[a] / (dist[a] - dist[b]);
    const int idx = static_cast<int>(out.vertices.size());
    out.vertices.push_back(in.vertices[a] + t * (in.vertices[b] - in.vertices[a]));
    onPlane.push_back(1);
    cutEdges.push_back({lo, hi, idx});
    return idx;
  };

  for (int f = 0; f < in.faceCount(); ++f) {
    const int s = in.faceStarts[f], e = in.faceStarts[f + 1];
    const std::size_t before = out.faceIndices.size();
    for (int k = s; k < e; ++k) {
      const int i = in.faceIndices[k];
      const int j = in.faceIndices[k + 1 < e ? k + 1 : s];
      const bool iOut = dist[i] > tol, jOut = dist[j] > tol;
      if (!iOut) out.faceIndices.push_back(keep(i));
      const bool iIn = dist[i] < -tol, jIn = dist[j] < -tol;
      if ((iIn && jOut) || (iOut && jIn)) out.faceIndices.push_back(cut(i, j));
    }
    if (out.faceIndices.size() - before >= 3)
      out.faceStarts.push_back(static_cast<int>(out.faceIndices.size()));
    else
      out.faceIndices.resize(before);  // face cut away or reduced to an edge/point on the plane
  }

  // Cap face: the output vertices on the plane that are used by a kept face, in counter-
  // clockwise order around +normal (the outward normal of the cap).
  thread_local std::vector<char> used;
  used.assign(out.vertices.size(), 0);
  for (int idx : out.faceIndices) used[idx] = 1;
  thread_local std::vector<int> cap;
  cap.clear();
  Vec3 centre = Vec3::Zero();
  for (int i = 0; i < static_cast<int>(out.vertices.size()); ++i)
    if (used[i] && onPlane[i]) {
      cap.push_back(i);
      centre += out.vertices[i];
    }
  if (cap.size() >= 3) {
    centre /= static_cast<double>(cap.size());
    const Vec3 n = plane.normal.normalized();
    const Vec3 u = n.unitOrthogonal();
    const Vec3 v = n.cross(u);
    thread_local std::vector<std::pair<double, int>> angles;
    angles.clear();
    for (int i : cap) {
      const Vec3 d = out.vertices[i] - centre;
      angles.emplace_back(std::atan2(d.dot(v), d.dot(u)), i);
    }
    std::sort(angles.begin(), angles.end());
    for (const auto& [angle, i] : angles) out.faceIndices.push_back(i);
    out.faceStarts.push_back(static_cast<int>(out.faceIndices.size()));
  }
  if (out.empty()) {
    out.vertices.clear();
    out.faceIndices.clear();
    out.faceStarts.assign(1, 0);
    return;
  }
  // Drop vertices no face uses (kept-side vertices are all used; this is for safety when a
  // degenerate face was dropped) so that later "all on one side" tests see only real vertices.
  bool allUsed = true;
  for (std::size_t i = 0; i < out.vertices.size(); ++i) allUsed = allUsed && used[i];
  if (!allUsed) {
    thread_local std::vector<int> compact;
    compact.assign(out.vertices.size(), -1);
    int n = 0;
    for (std::size_t i = 0; i < out.vertices.size(); ++i)
      if (used[i]) {
        compact[i] = n;
        out.vertices[n++] = out.vertices[i];
      }
    out.vertices.resize(n);
    for (int& idx : out.faceIndices) idx = compact[idx];
  }
}

ConvexPolytope clipped(const ConvexPolytope& in, const Plane& plane) {
  ConvexPolytope out;
  clip(in, plane, out);
  return out;
}

namespace {

// Clips poly successively by the planes, ping-ponging between two buffers.
double volumeAfterClips(ConvexPolytope poly, std::span<const Plane> planes) {
  ConvexPolytope tmp;
  for (const Plane& pl : planes) {
    if (poly.empty()) return 0.0;
    clip(poly, pl, tmp);
    std::swap(poly, tmp);
  }
  return poly.volume();
}

void checkAxis(int axis, const char* who) {
  if (axis < 0 || axis > 2) throw std::invalid_argument(fmt::format("{}: axis must be 0, 1 or 2 (got {})", who, axis));
}

}  // namespace

double clippedVolume(const PlacedPolyhedron& p, std::span<const Plane> halfSpaces) {
  return volumeAfterClips(toPolytope(p), halfSpaces);
}

double intersectionVolume(const PlacedPolyhedron& a, const PlacedPolyhedron& b) {
  if (a.shape == nullptr || b.shape == nullptr)
    throw std::invalid_argument("intersectionVolume: PlacedPolyhedron.shape is null");
  // Cheap rejection by bounding spheres before any clipping.
  const double reach = a.shape->boundingRadius() + b.shape->boundingRadius();
  if ((a.position - b.position).squaredNorm() > reach * reach) return 0.0;
  // b's face planes in world space: n_w = R n, offset_w = n_b.offset + n_w . position.
  std::vector<Plane> planes;
  planes.reserve(b.shape->faceNormals().size());
  for (std::size_t f = 0; f < b.shape->faceNormals().size(); ++f) {
    const Vec3 n = b.rotation * b.shape->faceNormals()[f];
    planes.push_back({n, b.shape->faceOffsets()[f] + n.dot(b.position)});
  }
  return volumeAfterClips(toPolytope(a), planes);
}

double slabVolume(const PlacedPolyhedron& p, int axis, double lo, double hi) {
  checkAxis(axis, "slabVolume");
  if (!(hi > lo)) return 0.0;
  Vec3 e = Vec3::Zero();
  e[axis] = 1.0;
  const Plane planes[2] = {{e, hi}, {-e, -lo}};
  return clippedVolume(p, planes);
}

double boxVolume(const PlacedPolyhedron& p, const Vec3& lo, const Vec3& hi) {
  if (!((hi - lo).minCoeff() > 0.0)) return 0.0;
  const Plane planes[6] = {{Vec3::UnitX(), hi.x()},   {-Vec3::UnitX(), -lo.x()}, {Vec3::UnitY(), hi.y()},
                           {-Vec3::UnitY(), -lo.y()}, {Vec3::UnitZ(), hi.z()},   {-Vec3::UnitZ(), -lo.z()}};
  return clippedVolume(p, planes);
}

namespace {

// Splits poly at x[axis] = edges[i] for increasing edges and calls fn(i, piece) for the piece
// in [edges[i], edges[i+1]). Each cut keeps the part below the plane and carries the part above
// to the next cut, so every piece costs two clips of an ever smaller polytope.
template <typename Fn>
void sweepSlabs(const ConvexPolytope& poly, int axis, std::span<const double> edges, Fn&& fn) {
  if (edges.size() < 2 || poly.empty()) return;
  Vec3 e = Vec3::Zero();
  e[axis] = 1.0;
  ConvexPolytope rest, below, next;
  clip(poly, Plane{-e, -edges[0]}, rest);
  for (std::size_t i = 0; i + 1 < edges.size() && !rest.empty(); ++i) {
    clip(rest, Plane{e, edges[i + 1]}, below);
    if (!below.empty()) fn(static_cast<int>(i), below);
    clip(rest, Plane{-e, -edges[i + 1]}, next);
    std::swap(rest, next);
  }
}

}  // namespace

std::vector<double> slabVolumes(const PlacedPolyhedron& p, int axis, std::span<const double> edges) {
  checkAxis(axis, "slabVolumes");
  for (std::size_t i = 0; i + 1 < edges.size(); ++i)
    if (!(edges[i + 1] > edges[i])) throw std::invalid_argument("slabVolumes: edges must be strictly increasing");
  std::vector<double> out(edges.size() < 2 ? 0 : edges.size() - 1, 0.0);
  sweepSlabs(toPolytope(p), axis, edges, [&](int i, const ConvexPolytope& piece) { out[i] = piece.volume(); });
  return out;
}

void forEachCellVolume(const PlacedPolyhedron& p, const Vec3& origin, double h,
                       const std::function<void(int, int, int, double)>& fn) {
  if (!(h > 0.0))
    throw std::invalid_argument(fmt::format("forEachCellVolume: cell side h must be positive (got {})", h));
  const ConvexPolytope poly = toPolytope(p);
  // Cell index range along an axis from the bounds of a piece.
  auto range = [&](const ConvexPolytope& piece, int axis, int& first, std::vector<double>& edges) {
    const auto [lo, hi] = piece.bounds();
    first = static_cast<int>(std::floor((lo[axis] - origin[axis]) / h));
    const int last = static_cast<int>(std::floor((hi[axis] - origin[axis]) / h));
    edges.clear();
    for (int i = first; i <= last + 1; ++i) edges.push_back(origin[axis] + h * i);
  };
  std::vector<double> ex, ey, ez;
  int fx = 0;
  range(poly, 0, fx, ex);
  sweepSlabs(poly, 0, ex, [&](int ix, const ConvexPolytope& slab) {
    int fy = 0;
    range(slab, 1, fy, ey);
    sweepSlabs(slab, 1, ey, [&](int iy, const ConvexPolytope& column) {
      int fz = 0;
      range(column, 2, fz, ez);
      sweepSlabs(column, 2, ez, [&](int iz, const ConvexPolytope& cell) {
        const double v = cell.volume();
        if (v > 0.0) fn(fx + ix, fy + iy, fz + iz, v);
      });
    });
  });
}

}  // namespace confpack::collision
