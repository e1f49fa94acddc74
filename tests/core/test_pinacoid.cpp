// The pinacoid (core/pinacoid.hpp; docs/model.md, "Pinacoids"): its topology, its closed-form dimensions, its
// symmetries and its mass properties.
#include <catch2/catch.hpp>
#include <cmath>
#include <set>

#include "core/grain.hpp"
#include "core/pinacoid.hpp"

using namespace confpack::core;

TEST_CASE("pinacoid has 8 vertices, 14 edges, 4 triangles and 4 trapezoids") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{});
  CHECK(p.vertices().size() == 8);
  CHECK(p.edges().size() == 14);
  CHECK(p.faces().size() == 8);
  int triangles = 0, quads = 0;
  for (const auto& f : p.faces()) (f.size() == 3 ? triangles : quads)++;
  CHECK(triangles == 4);
  CHECK(quads == 4);
  // Euler characteristic of a convex polyhedron.
  CHECK(p.vertices().size() - p.edges().size() + p.faces().size() == 2);
}

TEST_CASE("pinacoid ridge half-length follows l = L/2 - (E/2)/tan(alpha)") {
  CHECK(pinacoidRidgeHalfLength(1.0, PinacoidParams{}) == Approx(0.5 - 0.5 / std::sqrt(3.0)).epsilon(1e-14));
  CHECK(pinacoidRidgeHalfLength(1.0, PinacoidParams{}) == Approx(0.2113).margin(5e-5));
}

TEST_CASE("pinacoid has three mirror planes") {
  PinacoidParams params{0.8, 0.7, 55.0};
  const ConvexPolyhedron p = makePinacoid(1.3, params);
  for (int axis = 0; axis < 3; ++axis) {
    for (const Vec3& v : p.vertices()) {
      Vec3 m = v;
      m[axis] = -m[axis];
      double best = 1e9;
      for (const Vec3& w : p.vertices()) best = std::min(best, (w - m).norm());
      CHECK(best < 1e-14);
    }
  }
}

TEST_CASE("pinacoid triangles and trapezoids are isosceles") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{0.9, 0.8, 62.0});
  const auto& v = p.vertices();
  for (const auto& f : p.faces()) {
    if (f.size() == 3) {
      // Two of the three sides are equal.
      const double a = (v[f[0]] - v[f[1]]).norm(), b = (v[f[1]] - v[f[2]]).norm(), c = (v[f[2]] - v[f[0]]).norm();
      CHECK((std::abs(a - b) < 1e-12 || std::abs(b - c) < 1e-12 || std::abs(c - a) < 1e-12));
    } else {
      // Legs (sides 1 and 3 of the loop) of equal length, bases parallel.
      const double leg1 = (v[f[1]] - v[f[2]]).norm(), leg2 = (v[f[3]] - v[f[0]]).norm();
      CHECK(leg1 == Approx(leg2).epsilon(1e-12));
      const Vec3 b1 = (v[f[1]] - v[f[0]]).normalized(), b2 = (v[f[2]] - v[f[3]]).normalized();
      CHECK(std::abs(b1.dot(b2)) == Approx(1.0).epsilon(1e-12));
    }
  }
}

TEST_CASE("pinacoid mass properties: closed forms equal the divergence theorem") {
  for (const PinacoidParams& params :
       {PinacoidParams{}, PinacoidParams{0.7, 0.5, 45.0}, PinacoidParams{1.2, 0.9, 70.0}}) {
    for (double L : {1.0, 0.5, 1.37}) {
      const MassProperties closed = pinacoidMassProperties(L, params);
      const MassProperties numeric = makePinacoid(L, params).massProperties();
      CHECK(numeric.volume == Approx(closed.volume).epsilon(1e-12));
      CHECK(numeric.centroid.norm() < 1e-13 * L);
      CHECK((numeric.secondMoment - closed.secondMoment).norm() < 1e-12 * closed.secondMoment.norm());
      // V = E G (L + l) / 3.
      const double l = pinacoidRidgeHalfLength(L, params);
      CHECK(closed.volume == Approx(params.heightRatio * L * params.widthRatio * L * (L + l) / 3.0).epsilon(1e-14));
    }
  }
}
