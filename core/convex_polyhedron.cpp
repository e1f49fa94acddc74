#include "core/convex_polyhedron.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>
#include <stdexcept>

namespace confpack::core {

ConvexPolyhedron::ConvexPolyhedron(std::vector<Vec3> vertices, std::vector<std::vector<int>> faces)
    : vertices_(std::move(vertices)), faces_(std::move(faces)) {
  double scale = 0.0;
  for (const Vec3& v : vertices_) scale = std::max(scale, v.norm());
  boundingRadius_ = scale;
  const double tol = 1e-9 * std::max(scale, 1e-300);

  std::set<std::pair<int, int>> edgeSet;
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    const auto& loop = faces_[f];
    if (loop.size() < 3) throw std::invalid_argument(fmt::format("polyhedron: face {} has fewer than 3 vertices", f));
    // Newell's method: robust normal for a planar polygon.
    Vec3 n = Vec3::Zero();
    Vec3 centre = Vec3::Zero();
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec3& a = vertices_.at(loop[i]);
      const Vec3& b = vertices_.at(loop[(i + 1) % loop.size()]);
      n += a.cross(b);
      centre += a;
    }
    if (n.norm() <= tol * tol) throw std::invalid_argument(fmt::format("polyhedron: face {} is degenerate", f));
    n.normalize();
    centre /= static_cast<double>(loop.size());
    normals_.push_back(n);
    offsets_.push_back(n.dot(centre));
    for (std::size_t i = 0; i < loop.size(); ++i) {
      int a = loop[i], b = loop[(i + 1) % loop.size()];
      edgeSet.emplace(std::min(a, b), std::max(a, b));
    }
  }
  for (const auto& [a, b] : edgeSet) edges_.push_back({a, b});
  for (std::size_t f = 0; f < faces_.size(); ++f)
    for (std::size_t v = 0; v < vertices_.size(); ++v)
      if (normals_[f].dot(vertices_[v]) - offsets_[f] > tol)
        throw std::invalid_argument(
            fmt::format("polyhedron: vertex {} lies outside face {} (not convex or badly oriented)", v, f));
}

int ConvexPolyhedron::supportIndex(const Vec3& dir) const {
  int best = 0;
  double bestDot = vertices_[0].dot(dir);
  for (int i = 1; i < static_cast<int>(vertices_.size()); ++i) {
    const double d = vertices_[i].dot(dir);
    if (d > bestDot) {
      bestDot = d;
      best = i;
    }
  }
  return best;
}

MassProperties ConvexPolyhedron::massProperties() const {
  // Divergence theorem through signed tetrahedra (0, a, b, c) of a fan triangulation of every
  // face: V = det[a b c]/6, int x dV = V (a+b+c)/4,
  // int x x^T dV = V/20 (a a^T + b b^T + c c^T + s s^T) with s = a+b+c (Tonon 2004).
  double volume = 0.0;
  Vec3 first = Vec3::Zero();
  Mat3 second = Mat3::Zero();
  for (const auto& loop : faces_) {
    const Vec3& a = vertices_[loop[0]];
    for (std::size_t i = 1; i + 1 < loop.size(); ++i) {
      const Vec3& b = vertices_[loop[i]];
      const Vec3& c = vertices_[loop[i + 1]];
      const double v = a.dot(b.cross(c)) / 6.0;
      const Vec3 s = a + b + c;
      volume += v;
      first += v * s / 4.0;
      second += v / 20.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
    }
  }
  MassProperties mp;
  mp.volume = volume;
  mp.centroid = first / volume;
  mp.secondMoment = second - volume * mp.centroid * mp.centroid.transpose();
  return mp;
}

bool ConvexPolyhedron::contains(const Vec3& p, double tol) const {
  for (std::size_t f = 0; f < faces_.size(); ++f)
    if (normals_[f].dot(p) - offsets_[f] > tol) return false;
  return true;
}

ConvexPolyhedron ConvexPolyhedron::scaled(double s) const {
  ConvexPolyhedron c = *this;
  for (Vec3& v : c.vertices_) v *= s;
  for (double& o : c.offsets_) o *= s;
  c.boundingRadius_ *= s;
  return c;
}

}  // namespace confpack::core
