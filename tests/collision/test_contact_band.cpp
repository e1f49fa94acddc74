// The contact type by a distance band (collision/contact_band): a face tilted by a few degrees
// reads as a face in the band and not in the exact rule; a vertex or an edge on a face keeps its
// type; the wall reading against a count of the vertices within the band; symmetry and bad input.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "collision/contact_band.hpp"
#include "core/pinacoid.hpp"
#include "tests/support/polyhedra.hpp"

using namespace confpack::core;
using namespace confpack::collision;
using namespace confpack::testing;

namespace {

// b turned by angle_deg about the line through `pivot` along `axis`.
PlacedPolyhedron turned(const PlacedPolyhedron& b, const Vec3& pivot, const Vec3& axis, double angle_deg) {
  const Mat3 r = Eigen::AngleAxisd(angle_deg * std::numbers::pi / 180.0, axis.normalized()).toRotationMatrix();
  return {b.shape, pivot + r * (b.position - pivot), r * b.rotation};
}

}  // namespace

TEST_CASE("contact band: a face tilted by 3 degrees on a face is triple in the band, not in the exact rule") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  // b's bottom trapezoid (face 3) lies on a's top trapezoid (face 0, plane y + z = 1/2): b is a
  // translated by twice the face's offset along its normal (the pinacoid is symmetric through its
  // centre).
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  const PlacedPolyhedron b{&p, kN1 * (2 * kOff1), Mat3::Identity()};
  CHECK(classifyContact(a, b) == ContactType::Triple);
  CHECK(classifyContactBand(a, b, 0.1) == ContactType::Triple);
  // Tilted by 3 degrees about the x axis (in the face plane) through the middle of the contact:
  // the face's edges at +-0.354 across rise and sink by 0.0185, within the band of 0.1 but far
  // beyond the exact rule's milliradian.
  const Vec3 pivot(0.0, 0.25, 0.25);
  REQUIRE(kN1.dot(pivot) == Approx(kOff1));
  for (double angle : {3.0, -3.0}) {
    INFO("tilt " << angle << " degrees");
    const PlacedPolyhedron tilted = turned(b, pivot, Vec3::UnitX(), angle);
    CHECK(classifyContact(a, tilted) != ContactType::Triple);
    CHECK(classifyContactBand(a, tilted, 0.1) == ContactType::Triple);
    CHECK(classifyContactBand(tilted, a, 0.1) == ContactType::Triple);
    // With the contact's normal imposed (a's face normal) too.
    CHECK(classifyContactBand(a, tilted, kN1, 0.1) == ContactType::Triple);
    // A band narrower than the tilt's rise (0.0185 on either side of the pivot) leaves one edge of
    // each face: their overlap is a segment.
    CHECK(classifyContactBand(a, tilted, 0.005) == ContactType::Double);
  }
}

TEST_CASE("contact band: a vertex on a face is simple, an edge on a face double") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  // b upside down on its top ridge (vertices 4 and 5 at z = -1/2 in b's frame) lying across a's
  // top ridge: the two ridges cross at one point.
  const Mat3 flipX = Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitX()).toRotationMatrix();
  const Mat3 quarter = Eigen::AngleAxisd(0.5 * std::numbers::pi, Vec3::UnitZ()).toRotationMatrix();
  const PlacedPolyhedron crossed{&p, Vec3(0, 0, 1.0), quarter * flipX};
  CHECK(classifyContactBand(a, crossed, 0.1) == ContactType::Simple);
  // The same ridges parallel, one above the other: a segment.
  const PlacedPolyhedron parallel{&p, Vec3(0, 0, 1.0), flipX};
  CHECK(classifyContactBand(a, parallel, 0.1) == ContactType::Double);
  // A corner of b (lowest vertex 0.2 below every other) on a's top trapezoid.
  std::mt19937_64 rng(11);
  int corners = 0;
  for (int trial = 0; trial < 200 && corners < 10; ++trial) {
    const Mat3 r = randomRotation(rng);
    const PlacedPolyhedron probe{&p, Vec3::Zero(), r};
    const Vec3 down = -kN1;
    auto verts = probe.worldVertices();
    std::sort(verts.begin(), verts.end(), [&](const Vec3& x, const Vec3& y) { return down.dot(x) > down.dot(y); });
    if (down.dot(verts[0]) - down.dot(verts[1]) < 0.2) continue;
    // Its lowest vertex on the middle of a's face.
    const Vec3 target = kN1 * kOff1;
    const PlacedPolyhedron b{&p, target - verts[0], r};
    INFO("trial " << trial);
    CHECK(classifyContactBand(a, b, 0.1) == ContactType::Simple);
    CHECK(classifyContact(a, b) == ContactType::Simple);
    ++corners;
  }
  CHECK(corners == 10);
}

TEST_CASE("contact band: a wall contact's type is the count of the grain's vertices within the band") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  // On the floor z = 0, touching: no three vertices of a pinacoid are on one line, so the type is
  // the number of vertices within w of the lowest, 1, 2, 3 or more.
  std::mt19937_64 rng(3);
  int counted[3] = {0, 0, 0};
  for (int trial = 0; trial < 300; ++trial) {
    const Mat3 r = randomRotation(rng);
    const PlacedPolyhedron probe{&p, Vec3::Zero(), r};
    double lowest = 1e300;
    for (const Vec3& x : probe.worldVertices()) lowest = std::min(lowest, x.z());
    const PlacedPolyhedron a{&p, Vec3(0.3, 0.2, -lowest), r};
    const double w = 0.1;
    int within = 0;
    for (const Vec3& x : a.worldVertices()) within += x.z() <= w;
    const ContactType expected =
        within == 1 ? ContactType::Simple : (within == 2 ? ContactType::Double : ContactType::Triple);
    CHECK(classifyPlaneContactBand(a, Vec3::Zero(), Vec3::UnitZ(), w) == expected);
    ++counted[static_cast<int>(expected)];
  }
  // Every type occurs among the random poses.
  CHECK(counted[0] > 0);
  CHECK(counted[1] > 0);
  CHECK(counted[2] > 0);
  // A face 3 degrees off the floor: triple in the band, not in the exact rule.
  const Vec3 nf = p.faceNormals()[3];
  const Mat3 flat = Quat::FromTwoVectors(nf, -Vec3::UnitZ()).toRotationMatrix();
  const PlacedPolyhedron lying{&p, Vec3(0, 0, p.faceOffsets()[3]), flat};
  const PlacedPolyhedron tilted = turned(lying, Vec3::Zero(), Vec3::UnitX(), 3.0);
  CHECK(classifyPlaneContact(lying, Vec3::UnitZ()) == ContactType::Triple);
  CHECK(classifyPlaneContact(tilted, Vec3::UnitZ()) != ContactType::Triple);
  CHECK(classifyPlaneContactBand(tilted, Vec3::Zero(), Vec3::UnitZ(), 0.1) == ContactType::Triple);
}

TEST_CASE("contact band: swapping the bodies keeps the type") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{0.8, 0.9, 58.0});
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  for (int trial = 0; trial < 100; ++trial) {
    const PlacedPolyhedron a{&p, Vec3::Zero(), randomRotation(rng)};
    const Vec3 d = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized() * (0.6 + 0.2 * std::abs(gauss(rng)));
    const PlacedPolyhedron b{&p, d, randomRotation(rng)};
    for (double w : {0.02, 0.1, 0.3}) CHECK(classifyContactBand(a, b, w) == classifyContactBand(b, a, w));
  }
}

TEST_CASE("contact band: bad input is refused with a clear message") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  const PlacedPolyhedron b{&p, Vec3(0, 0, 1.0), Mat3::Identity()};
  for (double w : {0.0, -0.1, std::nan(""), HUGE_VAL})
    CHECK_THROWS_AS(classifyContactBand(a, b, w), std::invalid_argument);
  CHECK_THROWS_AS(classifyContactBand(a, PlacedPolyhedron{}, 0.1), std::invalid_argument);
  CHECK_THROWS_AS(classifyContactBand(a, b, Vec3::Zero(), 0.1), std::invalid_argument);
  CHECK_THROWS_AS(classifyPlaneContactBand(a, Vec3::Zero(), Vec3::Zero(), 0.1), std::invalid_argument);
}
