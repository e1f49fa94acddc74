// Contact features, regions and points (collision/contact_region): hand-placed pinacoid pairs
// with known types and points, random near-contact pairs whose points sit midway between the
// surfaces, and the reduction of large polygons.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "collision/polyhedron_contact.hpp"
#include "core/pinacoid.hpp"
#include "tests/support/polyhedra.hpp"

using namespace confpack::core;
using namespace confpack::collision;
using namespace confpack::testing;

TEST_CASE("contact: pinacoid vertex on a face is Simple with the face normal") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  std::mt19937_64 rng(1);
  const Mat3 r = randomRotation(rng);
  // b's lowest vertex along n1 sits above the point q of a's top face (y > 0), at height g.
  const int k = p.supportIndex(r.transpose() * (-kN1));
  const Vec3 q(0.05, 0.25, 0.25);  // on y + z = 1/2, inside the trapezoid
  for (double g : {0.01, 1e-7, 0.0, -1e-4, -0.005}) {
    const PlacedPolyhedron b{&p, q + g * kN1 - r * p.vertices()[k], r};
    const auto c = collidePolyhedra(a, b, 0.02);
    REQUIRE(c);
    CHECK(c->type == ContactType::Simple);
    CHECK(c->gap == Approx(g).margin(1e-14));
    CHECK((c->normal - kN1).norm() < 1e-12);
    CHECK(c->featureA == Feature{FeatureKind::Face, 0});
    CHECK(c->featureB == Feature{FeatureKind::Vertex, k});
    REQUIRE(c->points.size() == 1);
    CHECK((c->points[0] - (q + 0.5 * g * kN1)).norm() < 1e-12);
    CHECK(c->pointGaps[0] == Approx(g).margin(1e-14));
    CHECK(classifyContact(a, b) == ContactType::Simple);
  }
  // Beyond the alert distance: no contact.
  const PlacedPolyhedron far{&p, q + 0.03 * kN1 - r * p.vertices()[k], r};
  CHECK_FALSE(collidePolyhedra(a, far, 0.02));
}

TEST_CASE("contact: crossing ridges are an edge-edge Simple contact") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  // b turned 90 degrees about z: its bottom ridge runs along y and crosses a's top ridge (along x).
  const Mat3 rz = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()).toRotationMatrix();
  for (double g : {0.003, 1e-9, 0.0, -0.002}) {
    const PlacedPolyhedron b{&p, Vec3(0.03, -0.02, 1.0 + g), rz};
    const auto c = collidePolyhedra(a, b, 0.01);
    REQUIRE(c);
    CHECK(c->type == ContactType::Simple);
    CHECK(c->gap == Approx(g).margin(1e-14));
    CHECK((c->normal - Vec3::UnitZ()).norm() < 1e-12);
    CHECK(c->featureA.kind == FeatureKind::Edge);
    CHECK(c->featureB.kind == FeatureKind::Edge);
    REQUIRE(c->points.size() == 1);
    CHECK((c->points[0] - Vec3(0.03, 0.0, 0.5 + 0.5 * g)).norm() < 1e-12);  // where the ridges cross
  }
}

TEST_CASE("contact: a ridge lying on a face is Double with the clipped edge ends") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  // Rotating b by -45 degrees about x sends its bottom ridge's outward bisector (0,0,-1) to -n1,
  // so the ridge lies flat on a's top face y + z = 1/2.
  const Mat3 rx = Eigen::AngleAxisd(-M_PI / 4, Vec3::UnitX()).toRotationMatrix();
  const Vec3 ridgeMid = rx * Vec3(0, 0, -0.5);
  const Vec3 q(0.0, 0.25, 0.25);  // mid-height of the trapezoid: its half-width there is (1/2 + l)/2
  const double halfWidth = 0.5 * (0.5 + kL);
  for (double g : {0.004, -0.003}) {
    SECTION("whole ridge on the face, g = " + std::to_string(g)) {
      const PlacedPolyhedron b{&p, q + g * kN1 - ridgeMid, rx};
      const auto c = collidePolyhedra(a, b, 0.01);
      REQUIRE(c);
      CHECK(c->type == ContactType::Double);
      CHECK(c->gap == Approx(g).margin(1e-14));
      CHECK((c->normal - kN1).norm() < 1e-12);
      CHECK(c->featureA == Feature{FeatureKind::Face, 0});
      CHECK(c->featureB.kind == FeatureKind::Edge);
      REQUIRE(c->points.size() == 2);
      const double x0 = std::min(c->points[0].x(), c->points[1].x());
      const double x1 = std::max(c->points[0].x(), c->points[1].x());
      CHECK(x0 == Approx(-kL).margin(1e-12));
      CHECK(x1 == Approx(kL).margin(1e-12));
      for (int i = 0; i < 2; ++i) {
        CHECK(c->pointGaps[i] == Approx(g).margin(1e-12));
        CHECK(std::abs(kN1.dot(c->points[i]) - (kOff1 + 0.5 * g)) < 1e-12);  // midway
      }
      CHECK(classifyContact(a, b) == ContactType::Double);
    }
    SECTION("ridge overhanging the face edge, g = " + std::to_string(g)) {
      const double shift = 0.3;  // ridge spans x in [0.3 - l, 0.3 + l]; the face ends at halfWidth
      const PlacedPolyhedron b{&p, q + g * kN1 - ridgeMid + Vec3(shift, 0, 0), rx};
      const auto c = collidePolyhedra(a, b, 0.01);
      REQUIRE(c);
      CHECK(c->type == ContactType::Double);
      REQUIRE(c->points.size() == 2);
      const double x0 = std::min(c->points[0].x(), c->points[1].x());
      const double x1 = std::max(c->points[0].x(), c->points[1].x());
      CHECK(x0 == Approx(shift - kL).margin(1e-12));
      CHECK(x1 == Approx(halfWidth).margin(1e-12));
    }
  }
}

TEST_CASE("contact: a ridge 0.3 degrees off a face has both ends as points within reach, each with its own gap") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  // b's bottom ridge (body frame: x in [-l, l] at z = -1/2) lies on a's top face (as above), then
  // turns by 0.3 degrees about x cross n1, so that its end at +x rises off the face by
  // 2 l sin(0.3 deg).
  const Mat3 rx = Eigen::AngleAxisd(-M_PI / 4, Vec3::UnitX()).toRotationMatrix();
  const Vec3 q(0.0, 0.25, 0.25);
  const double tilt = 0.3 * std::numbers::pi / 180.0;
  const Mat3 lift = Eigen::AngleAxisd(tilt, Vec3::UnitX().cross(kN1).normalized()).toRotationMatrix();
  const double alert = 0.03;
  for (double g : {0.002, 0.0, -0.003}) {
    // The low end (x = -l) at height g above the face; the ridge turned about it.
    const Vec3 lowEnd = q + Vec3(-kL, 0, 0) + g * kN1;
    const Mat3 r = lift * rx;
    const Vec3 centre = lowEnd - r * (Vec3(-kL, 0, 0) + Vec3(0, 0, -0.5));
    const PlacedPolyhedron b{&p, centre, r};
    std::vector<double> endGaps;
    for (const Vec3& v : b.worldVertices())
      if (kN1.dot(v) - kOff1 < g + alert) endGaps.push_back(kN1.dot(v) - kOff1);
    REQUIRE(endGaps.size() == 2);  // the ridge's two ends, and no other vertex of b, within reach
    std::sort(endGaps.begin(), endGaps.end());
    CHECK(endGaps[0] == Approx(g).margin(1e-12));
    CHECK(endGaps[1] - endGaps[0] == Approx(2.0 * kL * std::sin(tilt)).epsilon(1e-9));
    // The type's tolerance (1e-3 rad) sees a vertex on the face: one point, at the low end.
    const auto narrow = collidePolyhedra(a, b, alert);
    REQUIRE(narrow);
    CHECK(narrow->type == ContactType::Simple);
    CHECK(narrow->points.size() == 1);
    // Within reach of the alert distance: both ends, each with its own gap, on the face's normal.
    const auto reach = collidePolyhedra(a, b, alert, kFeatureAngleTol, alert);
    REQUIRE(reach);
    CHECK(reach->type == ContactType::Simple);
    CHECK((reach->normal - kN1).norm() < 1e-12);
    REQUIRE(reach->points.size() == 2);
    std::vector<double> gaps(reach->pointGaps.begin(), reach->pointGaps.end());
    std::sort(gaps.begin(), gaps.end());
    CHECK(gaps[0] == Approx(endGaps[0]).margin(1e-12));
    CHECK(gaps[1] == Approx(endGaps[1]).margin(1e-12));
    for (std::size_t i = 0; i < 2; ++i)  // midway between the face and the ridge end
      CHECK(kN1.dot(reach->points[i]) - kOff1 == Approx(0.5 * reach->pointGaps[i]).margin(1e-12));
  }
}

TEST_CASE("contact: trapezoid on trapezoid is Triple with every vertex of the hexagonal overlap as a point") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  // b unrotated: its bottom trapezoid y < 0 has normal -n1, so translating b by n1 (2 off + g)
  // puts that face on a's top face, flipped (long side on short side): the common polygon is a
  // hexagon, (x, s) = (+-l, 0), (+-(1/2+l)/2, 1/2), (+-l, 1) along the face's slant height.
  for (double g : {0.002, 0.0, -0.004}) {
    const Vec3 shift(0.0, 0.0, 0.0);
    const PlacedPolyhedron b{&p, kN1 * (2 * kOff1 + g) + shift, Mat3::Identity()};
    const auto c = collidePolyhedra(a, b, 0.01);
    REQUIRE(c);
    CHECK(c->type == ContactType::Triple);
    CHECK(c->gap == Approx(g).margin(1e-14));
    CHECK((c->normal - kN1).norm() < 1e-12);
    CHECK(c->featureA == Feature{FeatureKind::Face, 0});
    CHECK(c->featureB == Feature{FeatureKind::Face, 3});  // bottom trapezoid y < 0
    REQUIRE(c->points.size() == 6);
    for (std::size_t i = 0; i < c->points.size(); ++i) {
      CHECK(c->pointGaps[i] == Approx(g).margin(1e-12));
      // On the mid plane, inside both faces (within half the gap of each surface).
      CHECK(std::abs(kN1.dot(c->points[i]) - (kOff1 + 0.5 * g)) < 1e-12);
      CHECK(onSurfaceOrInside(a, c->points[i] - 0.5 * c->pointGaps[i] * kN1, 1e-12));
      CHECK(onSurfaceOrInside(b, c->points[i] + 0.5 * c->pointGaps[i] * kN1, 1e-12));
    }
    // The 6 points are the hexagon: its area is slant x (3 l + 1/2) / 2 (two trapezoids of
    // widths 2 l and 1/2 + l over half the slant height each), and it contains the projection
    // of b's centre of mass: a stable support.
    const Vec3 u = Vec3::UnitX(), v = kN1.cross(u);
    std::vector<Eigen::Vector2d> q;
    for (const Vec3& x : c->points) q.emplace_back(u.dot(x), v.dot(x));
    const int n = static_cast<int>(q.size());
    // order by angle around the mean
    Eigen::Vector2d m = Eigen::Vector2d::Zero();
    for (auto& x : q) m += x / n;
    std::sort(q.begin(), q.end(), [&](auto& s, auto& t) {
      return std::atan2(s.y() - m.y(), s.x() - m.x()) < std::atan2(t.y() - m.y(), t.x() - m.x());
    });
    double area = 0;
    for (int i = 0; i < n; ++i) area += 0.5 * (q[i].x() * q[(i + 1) % n].y() - q[i].y() * q[(i + 1) % n].x());
    const double slant = std::sqrt(0.5);
    CHECK(area == Approx(slant * (3 * kL + 0.5) / 2).epsilon(1e-12));
    const Eigen::Vector2d com(u.dot(b.position), v.dot(b.position));
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d e = q[(i + 1) % n] - q[i], w = com - q[i];
      CHECK(e.x() * w.y() - e.y() * w.x() > 0.05);  // strictly inside, with margin
    }
    CHECK(classifyContact(a, b) == ContactType::Triple);
  }
}

TEST_CASE("contact: slightly tilted face on face keeps Triple and gives per-point gaps") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  const double tilt = 4e-4;  // rad, below the default angular tolerance 1e-3
  const Mat3 r = Eigen::AngleAxisd(tilt, Vec3::UnitX().cross(kN1).normalized()).toRotationMatrix() *
                 Eigen::AngleAxisd(tilt, Vec3::UnitX()).toRotationMatrix();
  const PlacedPolyhedron b{&p, kN1 * (2 * kOff1 + 0.003), r};
  const auto c = collidePolyhedra(a, b, 0.01);
  REQUIRE(c);
  CHECK(c->type == ContactType::Triple);
  REQUIRE(c->points.size() >= 3);
  // Each point is midway: point - gap/2 n lies on a's face plane, point + gap/2 n on b's face.
  const Vec3 nb = r * p.faceNormals()[3];
  const double offB = p.faceOffsets()[3] + nb.dot(b.position);
  double minGap = 1e9, maxGap = -1e9;
  for (std::size_t i = 0; i < c->points.size(); ++i) {
    const Vec3 onA = c->points[i] - 0.5 * c->pointGaps[i] * c->normal;
    const Vec3 onB = c->points[i] + 0.5 * c->pointGaps[i] * c->normal;
    CHECK(std::abs(kN1.dot(onA) - kOff1) < 1e-12);
    CHECK(std::abs(nb.dot(onB) - offB) < 1e-12);
    minGap = std::min(minGap, c->pointGaps[i]);
    maxGap = std::max(maxGap, c->pointGaps[i]);
  }
  CHECK(maxGap - minGap > 1e-5);  // the tilt shows in the gaps
  CHECK(minGap >= c->gap - 1e-12);
  // With a tighter tolerance than the tilt, the same pose is a vertex contact.
  const auto tight = collidePolyhedra(a, b, 0.01, 1e-5);
  REQUIRE(tight);
  CHECK(tight->type == ContactType::Simple);
  CHECK(classifyContact(a, b, 1e-5) == ContactType::Simple);
  CHECK(classifyContact(a, b) == ContactType::Triple);
}

TEST_CASE("contact: random near-contact pairs give consistent points, gaps and types") {
  // A solver may ask for a large angular tolerance (more predictive points) or none at all:
  // same guarantees.
  const double angleTol = GENERATE(0.0, 1e-3, 0.05);
  // Pairs brought to a random gap in [-0.01, 0.01] along their own normal. Every point must sit
  // midway between two surface points (point -+ gap/2 normal on a's and b's surface), no point
  // gap may be below the pair gap, and the point count must match the type.
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> uni(-0.01, 0.01);
  int tested = 0, doubles = 0;
  double worst = 0.0;
  for (int trial = 0; trial < 10000; ++trial) {
    const PlacedPolyhedron a{&p, Vec3::Zero(), randomRotation(rng)};
    PlacedPolyhedron b{&p, Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized() * 1.5, randomRotation(rng)};
    const double target = uni(rng);
    auto c = collidePolyhedra(a, b, 10.0, angleTol);
    for (int k = 0; k < 5 && c; ++k) {
      b.position += (target - c->gap) * c->normal;
      c = collidePolyhedra(a, b, 10.0, angleTol);
    }
    REQUIRE(c);
    if (std::abs(c->gap - target) > 1e-9) continue;  // the normal still turned: not a fixed point
    ++tested;
    const std::size_t np = c->points.size();
    REQUIRE(c->pointGaps.size() == np);
    if (c->type == ContactType::Simple) CHECK(np == 1);
    if (c->type == ContactType::Double) {
      CHECK(np == 2);
      ++doubles;
    }
    if (c->type == ContactType::Triple) CHECK((np >= 3 && np <= 8));  // every polygon vertex
    CHECK(std::abs(c->normal.norm() - 1.0) < 1e-14);
    for (std::size_t i = 0; i < np; ++i) {
      CHECK(c->pointGaps[i] >= c->gap - 1e-9);
      const double da = std::abs(signedFacePlaneMax(a, c->points[i] - 0.5 * c->pointGaps[i] * c->normal));
      const double db = std::abs(signedFacePlaneMax(b, c->points[i] + 0.5 * c->pointGaps[i] * c->normal));
      worst = std::max({worst, da, db});
    }
  }
  INFO("angleTol " << angleTol << ", worst surface deviation " << worst << ", tested " << tested);
  // Nearly degenerate vertex-edge pairs are the worst (~1e-8): the closest points slide along
  // an edge almost perpendicular to the normal.
  CHECK(worst < 1e-7);
  CHECK(tested > 7500);
  if (angleTol > 0.0) CHECK(doubles > 10);  // random poses are never exactly edge-on-face
}

TEST_CASE("contact: a tilted face-face contact keeps every vertex of its polygon, each with its own gap") {
  // Trapezoid on flipped trapezoid (hexagonal overlap, see above) with b tilted by 3e-4 rad
  // about the slant direction of the face: the gap then grows linearly with x, so the deepest
  // points are the hexagon vertices (+-(1/2 + l)/2, s = 1/2). A reduction to fewer points would
  // let the dropped vertices sink into a unseen; all 6 must be there, the deepest at c->gap.
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const PlacedPolyhedron a{&p, Vec3::Zero(), Mat3::Identity()};
  const Vec3 slant = Vec3(0, -1, 1).normalized();
  for (double tilt : {3e-4, -3e-4}) {
    const PlacedPolyhedron b{&p, kN1 * (2 * kOff1 + 0.002), Eigen::AngleAxisd(tilt, slant).toRotationMatrix()};
    const auto c = collidePolyhedra(a, b, 0.01);
    REQUIRE(c);
    CHECK(c->type == ContactType::Triple);
    REQUIRE(c->points.size() == 6);
    for (std::size_t i = 0; i < c->points.size(); ++i) {
      // The gap at each point is the distance between the two surfaces along the normal there.
      CHECK(onSurfaceOrInside(a, c->points[i] - 0.5 * c->pointGaps[i] * c->normal, 1e-12));
      CHECK(onSurfaceOrInside(b, c->points[i] + 0.5 * c->pointGaps[i] * c->normal, 1e-12));
    }
    const auto deepest = std::min_element(c->pointGaps.begin(), c->pointGaps.end()) - c->pointGaps.begin();
    CHECK(c->pointGaps[deepest] == Approx(c->gap).margin(1e-9));
    CHECK(std::abs(c->points[deepest].x()) == Approx(0.5 * (0.5 + kL)).margin(1e-3));
    for (std::size_t i = 0; i < c->points.size(); ++i)  // the others are clearly higher: all distinct
      if (static_cast<std::ptrdiff_t>(i) != deepest) CHECK(c->pointGaps[i] > c->gap + 1e-5);
  }
}

TEST_CASE("contact: a polygon of more than 8 vertices is reduced to 4 points, the deepest among them") {
  // Two regular octagonal prisms face to face, one turned by 22.5 deg: their caps overlap in a
  // 16-gon. The upper one is tilted a little so that one vertex is deepest; it must be kept.
  std::vector<Vec3> v;
  std::vector<std::vector<int>> f(2);
  for (int k = 0; k < 8; ++k) {
    const double t = k * std::numbers::pi / 4;
    v.emplace_back(std::cos(t), std::sin(t), -0.5);
    v.emplace_back(std::cos(t), std::sin(t), 0.5);
    f[0].push_back(2 * (7 - k));  // bottom cap, outward -z: clockwise seen from above
    f[1].push_back(2 * k + 1);    // top cap, outward +z
    f.push_back({2 * k, 2 * ((k + 1) % 8), 2 * ((k + 1) % 8) + 1, 2 * k + 1});
  }
  const ConvexPolyhedron prism(v, f);
  const PlacedPolyhedron a{&prism, Vec3::Zero(), Mat3::Identity()};
  for (double tilt : {2e-4, -2e-4}) {
    const Mat3 r = Eigen::AngleAxisd(tilt, Vec3::UnitX()).toRotationMatrix() *
                   Eigen::AngleAxisd(std::numbers::pi / 8, Vec3::UnitZ()).toRotationMatrix();
    const PlacedPolyhedron b{&prism, Vec3(0, 0, 1.001), r};
    const auto c = collidePolyhedra(a, b, 0.01);
    REQUIRE(c);
    CHECK(c->type == ContactType::Triple);
    REQUIRE(c->points.size() == 4);
    const double lowest = *std::min_element(c->pointGaps.begin(), c->pointGaps.end());
    CHECK(lowest == Approx(c->gap).margin(1e-9));
  }
}
