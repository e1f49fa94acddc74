// ConvexPolyhedron (core/convex_polyhedron.hpp): mass properties by the divergence theorem and
// refusal of badly oriented faces.
#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/convex_polyhedron.hpp"

using namespace confpack::core;

TEST_CASE("divergence-theorem mass properties of a unit cube") {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.emplace_back(i & 1 ? 0.5 : -0.5, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5);
  // Faces CCW from outside.
  std::vector<std::vector<int>> f = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  const MassProperties mp = ConvexPolyhedron(v, f).massProperties();
  CHECK(mp.volume == Approx(1.0));
  CHECK((mp.inertia() - Mat3::Identity() / 6.0).norm() < 1e-14);
}

TEST_CASE("a badly oriented face is refused") {
  std::vector<Vec3> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  std::vector<std::vector<int>> good = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  CHECK_NOTHROW(ConvexPolyhedron(v, good));
  auto bad = good;
  std::swap(bad[0][1], bad[0][2]);
  CHECK_THROWS_AS(ConvexPolyhedron(v, bad), std::invalid_argument);
}
