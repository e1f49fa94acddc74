// The polyhedron narrow phase's entry points (collision/polyhedron_contact): symmetry of a pair,
// polyhedron-plane and polyhedron-sphere contacts (the latter against FCL), the classifier, and
// bad input.
#include <fcl/fcl.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include "collision/polyhedron_contact.hpp"
#include "core/pinacoid.hpp"
#include "tests/support/polyhedra.hpp"

using namespace confpack::core;
using namespace confpack::collision;
using namespace confpack::testing;

TEST_CASE("contact: swapping the bodies negates the normal and keeps gap and type") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{0.8, 0.9, 58.0});
  std::mt19937_64 rng(99);
  std::normal_distribution<double> gauss;
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const PlacedPolyhedron a{&p, Vec3::Zero(), randomRotation(rng)};
    const Vec3 d = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized() * (0.6 + 0.3 * std::abs(gauss(rng)));
    const PlacedPolyhedron b{&p, d, randomRotation(rng)};
    const auto ab = collidePolyhedra(a, b, 0.05);
    const auto ba = collidePolyhedra(b, a, 0.05);
    REQUIRE(ab.has_value() == ba.has_value());
    if (!ab) continue;
    ++checked;
    CHECK(ab->gap == Approx(ba->gap).margin(1e-12));
    CHECK((ab->normal + ba->normal).norm() < 1e-9);
    CHECK(ab->type == ba->type);
    CHECK(ab->featureA == ba->featureB);
    CHECK(ab->featureB == ba->featureA);
  }
  CHECK(checked > 20);
  // The hand-placed face-face pair too.
  const ConvexPolyhedron q = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&q, Vec3::Zero(), Mat3::Identity()};
  const PlacedPolyhedron b{&q, kN1 * (2 * kOff1 - 0.001), Mat3::Identity()};
  const auto ab = collidePolyhedra(a, b, 0.01), ba = collidePolyhedra(b, a, 0.01);
  REQUIRE(ab);
  REQUIRE(ba);
  CHECK((ab->normal + ba->normal).norm() < 1e-12);
  CHECK(ab->type == ContactType::Triple);
  CHECK(ba->type == ContactType::Triple);
}

TEST_CASE("contact: pinacoid on the floor plane") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  // Bottom trapezoid y < 0 (face 3, normal (0,-1,-1)/sqrt2) turned to face straight down.
  const Vec3 nf = p.faceNormals()[3];
  const Mat3 r = Quat::FromTwoVectors(nf, -Vec3::UnitZ()).toRotationMatrix();
  const double h0 = p.faceOffsets()[3];  // centre height when the face rests on z = 0
  for (double g : {0.001, -0.0005}) {
    const PlacedPolyhedron a{&p, Vec3(2.0, 3.0, h0 + g), r};
    const auto c = collidePolyhedronPlane(a, Vec3::Zero(), Vec3::UnitZ(), 0.01);
    REQUIRE(c);
    CHECK(c->type == ContactType::Triple);
    CHECK(c->gap == Approx(g).margin(1e-14));
    CHECK((c->normal + Vec3::UnitZ()).norm() < 1e-15);
    CHECK(c->featureA == Feature{FeatureKind::Face, 3});
    REQUIRE(c->points.size() == 4);  // the 4 trapezoid corners
    for (std::size_t i = 0; i < 4; ++i) {
      CHECK(c->points[i].z() == Approx(0.5 * g).margin(1e-14));
      CHECK(c->pointGaps[i] == Approx(g).margin(1e-14));
    }
    CHECK(classifyPlaneContact(a, Vec3::UnitZ()) == ContactType::Triple);
  }
  // Resting on its top ridge (upside down on the ridge): Double; on a corner: Simple.
  const PlacedPolyhedron ridge{&p, Vec3(0, 0, 0.5), Mat3::Identity()};
  const auto cr = collidePolyhedronPlane(ridge, Vec3::Zero(), Vec3::UnitZ(), 0.01);
  REQUIRE(cr);
  CHECK(cr->type == ContactType::Double);
  CHECK(cr->points.size() == 2);
  CHECK(cr->gap == Approx(0.0).margin(1e-15));
  std::mt19937_64 rng(5);
  const PlacedPolyhedron corner{&p, Vec3(0, 0, 2.0), randomRotation(rng)};
  const auto cc = collidePolyhedronPlane(corner, Vec3(0, 0, 1.6), Vec3::UnitZ(), 1.0);
  REQUIRE(cc);
  CHECK(cc->type == ContactType::Simple);
  // A side wall y = W with inward normal -y: normal a -> wall is +y.
  const PlacedPolyhedron nearWall{&p, Vec3(0, 4.0 - 0.5 - 0.002, 1.0), Mat3::Identity()};
  const auto cw = collidePolyhedronPlane(nearWall, Vec3(0, 4.0, 0), -Vec3::UnitY(), 0.01);
  REQUIRE(cw);
  CHECK((cw->normal - Vec3::UnitY()).norm() < 1e-15);
  CHECK(cw->gap == Approx(0.002).margin(1e-14));
  CHECK(cw->type == ContactType::Double);  // the rectangle's long edge x in [-1/2, 1/2] at y = 1/2
  CHECK_FALSE(collidePolyhedronPlane(nearWall, Vec3(0, 4.0, 0), -Vec3::UnitY(), 0.001));
}

TEST_CASE("contact: sphere on a face, an edge and a vertex") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3(1, 1, 1), Mat3::Identity()};
  const double r = 0.3;
  SECTION("face") {
    const Vec3 q = a.position + Vec3(0.05, 0.25, 0.25);
    for (double g : {0.01, -0.02}) {
      const auto c = collidePolyhedronSphere(a, q + (r + g) * kN1, r, 0.05);
      REQUIRE(c);
      CHECK(c->gap == Approx(g).margin(1e-14));
      CHECK((c->normal - kN1).norm() < 1e-14);
      CHECK(c->featureA == Feature{FeatureKind::Face, 0});
      CHECK((c->points[0] - (q + 0.5 * g * kN1)).norm() < 1e-14);
      CHECK(c->type == ContactType::Simple);
    }
  }
  SECTION("edge: the top ridge, approached along its outward bisector") {
    const Vec3 q = a.position + Vec3(0.1, 0, 0.5);
    const Vec3 dir = Vec3(0, 0.3, 1).normalized();  // inside the ridge's normal cone
    const auto c = collidePolyhedronSphere(a, q + (r + 0.02) * dir, r, 0.05);
    REQUIRE(c);
    CHECK(c->gap == Approx(0.02).margin(1e-14));
    CHECK((c->normal - dir).norm() < 1e-13);
    CHECK(c->featureA.kind == FeatureKind::Edge);
  }
  SECTION("vertex: the mid-plane corner (1/2, 1/2, 0)") {
    const Vec3 q = a.position + Vec3(0.5, 0.5, 0);
    const Vec3 dir = Vec3(1, 1, 0.1).normalized();
    const auto c = collidePolyhedronSphere(a, q + (r + 0.03) * dir, r, 0.05);
    REQUIRE(c);
    CHECK(c->gap == Approx(0.03).margin(1e-14));
    CHECK((c->normal - dir).norm() < 1e-13);
    CHECK(c->featureA == Feature{FeatureKind::Vertex, 0});
    CHECK_FALSE(collidePolyhedronSphere(a, q + (r + 0.06) * dir, r, 0.05));
  }
  SECTION("centre inside the polyhedron") {
    const auto c = collidePolyhedronSphere(a, a.position + Vec3(0, 0.1, 0.2), r, 0.0);
    REQUIRE(c);
    // Nearest face plane y + z = 1/2 at distance (0.5 - 0.3)/sqrt2.
    CHECK(c->gap == Approx(-(0.2 / std::sqrt(2.0)) - r).margin(1e-14));
    CHECK((c->normal - kN1).norm() < 1e-14);
  }
}

TEST_CASE("contact: random separated sphere distances agree with FCL") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const auto shape = toFcl(p);
  std::mt19937_64 rng(8);
  std::normal_distribution<double> gauss;
  for (int trial = 0; trial < 100; ++trial) {
    const PlacedPolyhedron a{&p, Vec3::Zero(), randomRotation(rng)};
    const double r = 0.2 + 0.1 * std::abs(gauss(rng));
    const Vec3 centre = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized() * (0.8 + 0.3 * std::abs(gauss(rng)));
    const auto c = collidePolyhedronSphere(a, centre, r, 10.0);
    REQUIRE(c);
    if (c->gap < 1e-6) continue;
    fcl::Transform3d ta = fcl::Transform3d::Identity(), tb = fcl::Transform3d::Identity();
    ta.linear() = a.rotation;
    tb.translation() = centre;
    fcl::CollisionObjectd oa(shape, ta), ob(std::make_shared<fcl::Sphered>(r), tb);
    fcl::DistanceRequestd req;
    req.gjk_solver_type = fcl::GST_LIBCCD;
    req.distance_tolerance = 1e-13;
    fcl::DistanceResultd res;
    fcl::distance(&oa, &ob, req, res);
    CHECK(c->gap == Approx(res.min_distance).margin(1e-9));
    // And the contact point's surface point on a is on a's surface.
    const Vec3 onA = c->points[0] - 0.5 * c->gap * c->normal;
    CHECK(std::abs(signedFacePlaneMax(a, onA)) < 1e-12);
  }
}

TEST_CASE("contact: the classifier is independent of the normal a backend reports") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  const PlacedPolyhedron b{&p, kN1 * (2 * kOff1 - 0.001), Mat3::Identity()};
  CHECK(classifyContact(a, b) == ContactType::Triple);
  CHECK(classifyContact(a, b, kN1) == ContactType::Triple);
  // A normal a few 1e-4 rad off (what an approximate solver may report) still reads face-face.
  const Vec3 off = (kN1 + Vec3(2e-4, 0, 0)).normalized();
  CHECK(classifyContact(a, b, off) == ContactType::Triple);
  // Features, normal and points are deterministic keys: same call, same answer.
  const auto c1 = collidePolyhedra(a, b, 0.01), c2 = collidePolyhedra(a, b, 0.01);
  REQUIRE(c1);
  REQUIRE(c2);
  CHECK(c1->featureA == c2->featureA);
  CHECK(c1->points == c2->points);
}

TEST_CASE("contact: bad input is refused with a clear message") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  CHECK_THROWS_AS(collidePolyhedra(a, PlacedPolyhedron{}, 0.1), std::invalid_argument);
  CHECK_THROWS_AS(collidePolyhedra(a, a, -1.0), std::invalid_argument);
  CHECK_THROWS_AS(collidePolyhedronSphere(a, Vec3::Zero(), 0.0, 0.1), std::invalid_argument);
  CHECK_THROWS_AS(collidePolyhedronPlane(a, Vec3::Zero(), Vec3::Zero(), 0.1), std::invalid_argument);
}

TEST_CASE("contact: a wall contact keeps every vertex within alert, the deepest among them") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 50; ++trial) {
    const PlacedPolyhedron a{&p, Vec3(0, 0, 0.45), randomRotation(rng)};
    // An alert of 2 d takes all 8 vertices, each with its height above the plane as gap.
    const auto c = collidePolyhedronPlane(a, Vec3::Zero(), Vec3::UnitZ(), 2.0);
    REQUIRE(c);
    REQUIRE(c->points.size() == 8);
    std::vector<double> heights, gaps(c->pointGaps.begin(), c->pointGaps.end());
    for (const Vec3& x : a.worldVertices()) heights.push_back(x.z());
    std::sort(heights.begin(), heights.end());
    std::sort(gaps.begin(), gaps.end());
    for (int i = 0; i < 8; ++i) CHECK(gaps[i] == Approx(heights[i]).margin(1e-15));
    CHECK(c->gap == Approx(heights[0]).margin(1e-15));
  }
}
