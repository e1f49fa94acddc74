// The placed polyhedron in world coordinates (collision/world_polyhedron): its face planes, the
// faces and Gauss-map arc of each edge, and the point-in-face test, on rotated pinacoids.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "collision/world_polyhedron.hpp"
#include "core/pinacoid.hpp"
#include "tests/support/polyhedra.hpp"

using namespace confpack::core;
using namespace confpack::collision;
using namespace confpack::testing;

TEST_CASE("world polyhedron: every face plane holds its vertices and bounds the others") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const PlacedPolyhedron placed{&p, Vec3(0.3 * trial, -1.5, 2.0 + 0.1 * trial), randomRotation(rng)};
    const WorldPolyhedron w(placed);
    REQUIRE(w.v.size() == p.vertices().size());
    REQUIRE(w.n.size() == p.faces().size());
    for (std::size_t f = 0; f < w.n.size(); ++f) {
      CHECK(std::abs(w.n[f].norm() - 1.0) < 1e-14);
      for (int i : p.faces()[f]) CHECK(std::abs(w.n[f].dot(w.v[i]) - w.off[f]) < 1e-13);
      for (const Vec3& x : w.v) CHECK(w.n[f].dot(x) <= w.off[f] + 1e-13);
      CHECK(w.n[f].dot(w.centre) < w.off[f]);  // the centre is interior
    }
  }
}

TEST_CASE("world polyhedron: each edge lies on its two faces and its arc normal runs along it") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  std::mt19937_64 rng(6);
  const PlacedPolyhedron placed{&p, Vec3(1.0, 2.0, 3.0), randomRotation(rng)};
  const WorldPolyhedron w(placed);
  const auto& edges = p.edges();
  REQUIRE(w.edgeFaces.size() == edges.size());
  REQUIRE(w.edgeArc.size() == edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto [f0, f1] = w.edgeFaces[e];
    REQUIRE(f0 >= 0);
    REQUIRE(f1 >= 0);
    CHECK(f0 != f1);
    for (int f : {f0, f1})
      for (int i : {edges[e][0], edges[e][1]}) CHECK(std::abs(w.n[f].dot(w.v[i]) - w.off[f]) < 1e-13);
    // Both face normals are orthogonal to the edge, so their cross product is along it.
    const Vec3 d = (w.v[edges[e][1]] - w.v[edges[e][0]]).normalized();
    CHECK(w.edgeArc[e].cross(d).norm() < 1e-12 * std::max(1.0, w.edgeArc[e].norm()));
    CHECK(w.edgeArc[e].norm() > 1e-3);  // adjacent faces of a pinacoid are not parallel
  }
  const WorldPolyhedron bare(placed, false);
  CHECK(bare.edgeFaces.empty());
  CHECK(bare.edgeArc.empty());
}

TEST_CASE("world polyhedron: a point projects inside a face at its centroid, not beyond an edge") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  std::mt19937_64 rng(7);
  const PlacedPolyhedron placed{&p, Vec3(-0.4, 0.2, 0.9), randomRotation(rng)};
  const WorldPolyhedron w(placed);
  for (std::size_t f = 0; f < w.n.size(); ++f) {
    const auto& loop = p.faces()[f];
    Vec3 c = Vec3::Zero();
    for (int i : loop) c += w.v[i];
    c /= static_cast<double>(loop.size());
    // Above the centroid along the normal, and below it: the projection is the centroid.
    CHECK(projectsInsideFace(w, static_cast<int>(f), c + 0.7 * w.n[f]));
    CHECK(projectsInsideFace(w, static_cast<int>(f), c - 0.2 * w.n[f]));
    // Beyond the first edge's midpoint, in the face plane, away from the centroid.
    const Vec3 mid = 0.5 * (w.v[loop[0]] + w.v[loop[1]]);
    CHECK_FALSE(projectsInsideFace(w, static_cast<int>(f), mid + 0.1 * (mid - c) + 0.3 * w.n[f]));
  }
}
