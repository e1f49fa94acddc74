// The common-plane reading of a polyhedron pair (collision/common_plane.cpp): a face-to-face pair
// within the band gets at most 4 points with the one gap of the pair, a tilted face included (the
// band, 0.1 x the centre-to-face distance 0.354, takes a 0.7-wide face tilted by up to about 2.9
// degrees);
// any other pair is read exactly.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

#include "collision/polyhedron_contact.hpp"
#include "collision/world_polyhedron.hpp"
#include "core/pinacoid.hpp"
#include "tests/support/polyhedra.hpp"

using namespace confpack::core;
using namespace confpack::collision;
using namespace confpack::testing;

namespace {

// B face to face on A's face 1 (normal kN1), B turned by `tiltDegrees` about x (an axis in the
// face plane) about the touching face's centre, then moved along kN1 so that the pair's gap is
// `gap`.
PlacedPolyhedron facingB(const ConvexPolyhedron& p, double tiltDegrees, double gap) {
  const Mat3 r = Eigen::AngleAxisd(tiltDegrees * std::numbers::pi / 180.0, Vec3::UnitX()).toRotationMatrix();
  const Vec3 faceCentre = kN1 * kOff1;  // B's face -kN1 sits here when B is at 2 kOff1 kN1
  PlacedPolyhedron b{&p, faceCentre + r * (kN1 * kOff1), r};
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  const auto c = collidePolyhedra(a, b, 1.0);
  b.position += (gap - c->gap) * c->normal;
  return b;
}

}  // namespace

TEST_CASE("common plane: a face tilted by 2 degrees is face to face, every point with the pair's one gap") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  const PlacedPolyhedron b = facingB(p, 2.0, 0.001);
  const WorldPolyhedron A(a), B(b);
  const auto exact = collideWorldPolyhedra(A, B, 0.05);
  const auto plane = collideCommonPlane(A, B, 0.05, 0.1);
  REQUIRE(exact);
  REQUIRE(plane);
  CHECK(exact->gap == Approx(0.001).margin(1e-9));
  // The exact reading: the tilted face touches along an edge, its points at their own gaps.
  CHECK(exact->type == ContactType::Double);
  // The common plane: a face-to-face contact, at most 4 points, all at the smallest gap although
  // the face's far side is more than 0.02 d away.
  CHECK(plane->type == ContactType::Triple);
  CHECK(plane->points.size() >= 3);
  CHECK(plane->points.size() <= 4);
  for (double g : plane->pointGaps) CHECK(g == plane->gap);
  CHECK(plane->gap == Approx(0.001).margin(1e-9));
  double farthest = 0.0;
  for (const Vec3& v : b.worldVertices()) farthest = std::max(farthest, kN1.dot(v) - kOff1);
  CHECK(farthest > 0.02);  // not vacuous: the face is open far beyond the one gap
}

TEST_CASE("common plane: an overlap is the gap of every point, and a narrower band reads the tilt as an edge") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const WorldPolyhedron A(PlacedPolyhedron{&p, Vec3::Zero(), Mat3::Identity()});
  const WorldPolyhedron flat(facingB(p, 0.0, -0.002));
  const auto c = collideCommonPlane(A, flat, 0.05, 0.1);
  REQUIRE(c);
  CHECK(c->type == ContactType::Triple);
  CHECK(c->points.size() == 4);  // the overlap of two facing quadrilaterals: 4 of its corners
  for (double g : c->pointGaps) CHECK(g == Approx(-0.002).margin(1e-9));
  // A 10-degree tilt leaves the face's far side outside a band of 0.01: read exactly (an edge).
  const WorldPolyhedron tilted(facingB(p, 10.0, 0.001));
  const auto narrow = collideCommonPlane(A, tilted, 0.05, 0.01);
  const auto exact = collideWorldPolyhedra(A, tilted, 0.05, kFeatureAngleTol, 0.05);
  REQUIRE(narrow);
  REQUIRE(exact);
  CHECK(narrow->type == exact->type);
  CHECK(narrow->points.size() == exact->points.size());
  CHECK(narrow->pointGaps[0] == exact->pointGaps[0]);
}

TEST_CASE("common plane: random pairs are either the exact contact or face to face with one gap") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  int faceToFace = 0, exactOnes = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const WorldPolyhedron A(PlacedPolyhedron{&p, Vec3::Zero(), randomRotation(rng)});
    const Vec3 d = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized() * (0.6 + 0.3 * std::abs(gauss(rng)));
    const WorldPolyhedron B(PlacedPolyhedron{&p, d, randomRotation(rng)});
    const auto plane = collideCommonPlane(A, B, 0.05, 0.1);
    const auto exact = collideWorldPolyhedra(A, B, 0.05, kFeatureAngleTol, 0.05);
    REQUIRE(plane.has_value() == exact.has_value());
    if (!plane) continue;
    CHECK(plane->gap == exact->gap);
    CHECK(plane->normal == exact->normal);
    if (plane->points.size() == exact->points.size() && plane->pointGaps == exact->pointGaps) {
      ++exactOnes;
      continue;
    }
    ++faceToFace;
    CHECK(plane->type == ContactType::Triple);
    CHECK(plane->points.size() <= 4);
    for (double g : plane->pointGaps) CHECK(g == plane->gap);
  }
  CHECK(exactOnes > 20);
  CHECK(faceToFace > 0);
}
