#include "analysis/grain_volumes.hpp"

#include <optional>
#include <stdexcept>

#include "analysis/sphere_geometry.hpp"

namespace confpack::analysis {

PlacedGrain::PlacedGrain(const core::Grain& g) : PlacedGrain(g, g.position) {}

PlacedGrain::PlacedGrain(const core::Grain& g, const core::Vec3& position) : shape(g.polyhedron()) {
  placed.shape = &shape;
  placed.position = position;
  placed.rotation = g.orientation.normalized().toRotationMatrix();
}

double grainSlabVolume(const core::Grain& g, int axis, double lo, double hi) {
  if (!(hi > lo)) return 0.0;
  if (g.shape == core::ShapeKind::Sphere) return sphereSlabVolume(0.5 * g.size, g.position[axis], lo, hi);
  const PlacedGrain p(g);
  return collision::slabVolume(p.placed, axis, lo, hi);
}

std::vector<double> grainSlabVolumes(const core::Grain& g, int axis, std::span<const double> edges, double period) {
  std::vector<double> out(edges.size() > 1 ? edges.size() - 1 : 0, 0.0);
  if (out.empty()) return out;
  const double reach = g.boundingRadius();
  std::optional<PlacedGrain> poly;
  if (g.shape == core::ShapeKind::Pinacoid) poly.emplace(g);
  for (int m = -1; m <= 1; ++m) {
    if (m != 0 && !(period > 0.0)) continue;
    const double shift = m * period;
    const double c = g.position[axis] + shift;
    // Skip images that cannot reach the slices.
    if (c + reach < edges.front() || c - reach > edges.back()) continue;
    if (g.shape == core::ShapeKind::Sphere) {
      for (std::size_t k = 0; k < out.size(); ++k) {
        if (edges[k + 1] < c - reach || edges[k] > c + reach) continue;
        out[k] += sphereSlabVolume(0.5 * g.size, c, edges[k], edges[k + 1]);
      }
    } else {
      // Shift the slice edges instead of the grain: same volumes, one polyhedron.
      std::vector<double> shifted(edges.begin(), edges.end());
      for (double& e : shifted) e -= shift;
      // Only the slices the grain can reach: keeps the sweep short for thin slices.
      std::size_t first = 0, last = out.size();
      while (first < out.size() && shifted[first + 1] < g.position[axis] - reach) ++first;
      while (last > first && shifted[last - 1] > g.position[axis] + reach) --last;
      if (first >= last) continue;
      const std::vector<double> v =
          collision::slabVolumes(poly->placed, axis, std::span<const double>(shifted.data() + first, last - first + 1));
      for (std::size_t k = 0; k < v.size(); ++k) out[first + k] += v[k];
    }
  }
  return out;
}

double grainBoxVolume(const core::Grain& g, const core::Vec3& lo, const core::Vec3& hi) {
  if (g.shape == core::ShapeKind::Sphere)
    throw std::invalid_argument("grainBoxVolume: exact sphere-box volumes are not implemented");
  const PlacedGrain p(g);
  return collision::boxVolume(p.placed, lo, hi);
}

collision::ConvexPolytope pinacoidIntersection(const collision::PlacedPolyhedron& a,
                                               const collision::PlacedPolyhedron& b) {
  collision::ConvexPolytope cur = collision::toPolytope(a), next;
  const auto& normals = b.shape->faceNormals();
  const auto& offsets = b.shape->faceOffsets();
  for (std::size_t f = 0; f < normals.size() && !cur.empty(); ++f) {
    // Body-frame face n.x <= o becomes (R n).y <= o + (R n).p in the world.
    const core::Vec3 n = b.rotation * normals[f];
    collision::clip(cur, collision::Plane{n, offsets[f] + n.dot(b.position)}, next);
    std::swap(cur, next);
  }
  return cur;
}

double grainOverlapVolume(const core::Grain& a, const core::Grain& b, const core::Vec3& separation) {
  if (a.shape != b.shape) throw std::invalid_argument("overlap volume of a sphere and a pinacoid is not supported");
  if (a.shape == core::ShapeKind::Sphere) return sphereLensVolume(0.5 * a.size, 0.5 * b.size, separation.norm());
  if (separation.norm() > a.boundingRadius() + b.boundingRadius()) return 0.0;
  const PlacedGrain pa(a), pb(b, a.position + separation);
  return pinacoidIntersection(pa.placed, pb.placed).volume();
}

}  // namespace confpack::analysis
