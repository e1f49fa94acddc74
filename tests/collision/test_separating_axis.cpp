// The separating-axis test (collision/separating_axis): for overlapping pinacoids the gap is minus
// the exact penetration depth, checked against a brute-force test over every axis.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "collision/polyhedron_contact.hpp"
#include "core/pinacoid.hpp"
#include "tests/support/polyhedra.hpp"

using namespace confpack::core;
using namespace confpack::collision;
using namespace confpack::testing;

TEST_CASE("contact: penetration depth is the exact minimum over all separating axes") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  std::mt19937_64 rng(42);
  std::normal_distribution<double> gauss;
  int overlapping = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const PlacedPolyhedron a{&p, Vec3::Zero(), randomRotation(rng)};
    const Vec3 d = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized() * (0.5 + 0.5 * std::abs(gauss(rng)) * 0.6);
    const PlacedPolyhedron b{&p, d, randomRotation(rng)};
    const double brute = bruteForceSat(a, b);
    if (brute > 0) continue;
    ++overlapping;
    const auto c = collidePolyhedra(a, b, 0.0);
    REQUIRE(c);
    CHECK(c->gap == Approx(brute).margin(1e-12));
    // Translating b by the depth along the normal (plus a hair) separates the pair.
    const PlacedPolyhedron moved{&p, d + (-c->gap + 1e-9) * c->normal, b.rotation};
    CHECK(bruteForceSat(a, moved) > 0);
  }
  CHECK(overlapping > 50);
}
