// Grain (core/grain.hpp): derived mass properties and bounding radius of both shapes.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "core/grain.hpp"

using namespace confpack::core;

TEST_CASE("sphere grain volume and inertia") {
  Grain g;
  g.size = 2.0;
  CHECK(g.volume() == Approx(4.0 / 3.0 * M_PI));
  CHECK(g.bodyInertia()(0, 0) == Approx(0.4 * g.volume() * 1.0));
  CHECK(g.boundingRadius() == 1.0);
}

TEST_CASE("pinacoid bounding radius is the farthest vertex") {
  Grain g;
  g.shape = ShapeKind::Pinacoid;
  g.size = 1.1;
  double r = 0;
  const ConvexPolyhedron poly = g.polyhedron();
  for (const Vec3& v : poly.vertices()) r = std::max(r, v.norm());
  CHECK(g.boundingRadius() == Approx(r).epsilon(1e-14));
}
