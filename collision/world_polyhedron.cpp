#include "collision/world_polyhedron.hpp"

#include <stdexcept>
#include <vector>

namespace confpack::collision {

void WorldPolyhedron::assign(const PlacedPolyhedron& p, bool withTopology) {
  if (p.shape == nullptr) throw std::invalid_argument("PlacedPolyhedron.shape is null");
  shape = p.shape;
  v.clear();
  n.clear();
  off.clear();
  edgeFaces.clear();
  edgeArc.clear();
  centre = Vec3::Zero();
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

bool projectsInsideFace(const WorldPolyhedron& w, int f, const Vec3& x) {
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

}  // namespace confpack::collision
