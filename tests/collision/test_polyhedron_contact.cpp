// Pinacoid narrow phase and contact classifier (collision/polyhedron_contact): hand-placed pairs with
// known answers, symmetry, and FCL / brute-force cross-checks.
#include <fcl/fcl.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>

#include "core/pinacoid.hpp"
#include "collision/polyhedron_contact.hpp"

using namespace confpack::core;
using namespace confpack::collision;

namespace {

const PinacoidParams kParams{};                           // L = G = E = 1, alpha = 60 deg
const double kL = pinacoidRidgeHalfLength(1.0, kParams);  // ridge half-length l
// Top trapezoid y > 0 of the unit pinacoid: the plane y + z = 1/2, normal (0,1,1)/sqrt2.
const Vec3 kN1 = Vec3(0, 1, 1).normalized();
const double kOff1 = 0.5 / std::sqrt(2.0);

Mat3 randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Quat q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}

bool onSurfaceOrInside(const PlacedPolyhedron& p, const Vec3& x, double tol) {
  return p.shape->contains(p.rotation.transpose() * (x - p.position), tol);
}

// Distance of world point x to the (closed) polyhedron p: 0 inside.
double signedFacePlaneMax(const PlacedPolyhedron& p, const Vec3& x) {
  const Vec3 b = p.rotation.transpose() * (x - p.position);
  double m = -1e300;
  for (std::size_t f = 0; f < p.shape->faceNormals().size(); ++f)
    m = std::max(m, p.shape->faceNormals()[f].dot(b) - p.shape->faceOffsets()[f]);
  return m;
}

std::shared_ptr<fcl::Convexd> toFcl(const ConvexPolyhedron& p) {
  auto verts = std::make_shared<std::vector<fcl::Vector3d>>(p.vertices().begin(), p.vertices().end());
  auto faces = std::make_shared<std::vector<int>>();
  for (const auto& loop : p.faces()) {
    faces->push_back(static_cast<int>(loop.size()));
    faces->insert(faces->end(), loop.begin(), loop.end());
  }
  return std::make_shared<fcl::Convexd>(verts, static_cast<int>(p.faces().size()), faces);
}

// Independent minimum-penetration check: max over ALL face normals and ALL edge-pair cross
// products (no Gauss-map pruning) of the support separation min_B u.x - max_A u.x.
double bruteForceSat(const PlacedPolyhedron& a, const PlacedPolyhedron& b) {
  const auto va = a.worldVertices(), vb = b.worldVertices();
  auto sep = [&](Vec3 u) {
    double maxA = -1e300, minB = 1e300;
    for (const Vec3& x : va) maxA = std::max(maxA, u.dot(x));
    for (const Vec3& x : vb) minB = std::min(minB, u.dot(x));
    double s1 = minB - maxA;
    double maxB = -1e300, minA = 1e300;
    for (const Vec3& x : vb) maxB = std::max(maxB, u.dot(x));
    for (const Vec3& x : va) minA = std::min(minA, u.dot(x));
    return std::max(s1, minA - maxB);  // either orientation of the axis
  };
  double best = -1e300;
  for (const Vec3& n : a.shape->faceNormals()) best = std::max(best, sep(a.rotation * n));
  for (const Vec3& n : b.shape->faceNormals()) best = std::max(best, sep(b.rotation * n));
  for (const auto& ea : a.shape->edges())
    for (const auto& eb : b.shape->edges()) {
      const Vec3 u = (va[ea[1]] - va[ea[0]]).cross(vb[eb[1]] - vb[eb[0]]);
      if (u.norm() > 1e-9) best = std::max(best, sep(u.normalized()));
    }
  return best;
}

}  // namespace

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

TEST_CASE("contact: separation distance and normal agree with FCL for random pairs") {
  const ConvexPolyhedron p = makePinacoid(1.0, kParams);
  const auto shape = toFcl(p);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  int compared = 0;
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const PlacedPolyhedron a{&p, Vec3(0.1, 0.2, 0.3), randomRotation(rng)};
    const Vec3 dir = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const PlacedPolyhedron b{&p, a.position + dir * (0.9 + 0.4 * std::abs(gauss(rng))), randomRotation(rng)};
    const auto c = collidePolyhedra(a, b, 10.0);
    REQUIRE(c);
    if (c->gap <= 1e-6) continue;  // only separated pairs: FCL's distance is unsigned
    fcl::Transform3d ta = fcl::Transform3d::Identity(), tb = fcl::Transform3d::Identity();
    ta.linear() = a.rotation;
    ta.translation() = a.position;
    tb.linear() = b.rotation;
    tb.translation() = b.position;
    fcl::CollisionObjectd oa(shape, ta), ob(shape, tb);
    fcl::DistanceRequestd req;
    req.enable_nearest_points = true;
    // libccd's GJK. FCL 0.7's own GJK (GST_INDEP) returned distances up to twice too large for
    // 3 of these 200 pairs (an independent Frank-Wolfe minimisation agreed with libccd and us).
    req.gjk_solver_type = fcl::GST_LIBCCD;
    req.distance_tolerance = 1e-13;
    fcl::DistanceResultd res;
    fcl::distance(&oa, &ob, req, res);
    worst = std::max(worst, std::abs(res.min_distance - c->gap));
    CHECK(c->gap == Approx(res.min_distance).margin(1e-9));
    const Vec3 fclNormal = (res.nearest_points[1] - res.nearest_points[0]).normalized();
    CHECK((fclNormal - c->normal).norm() < 1e-5);
    // The gap is also >= the SAT lower bound and the pair is truly that far: b moved by the gap
    // along -normal touches a.
    CHECK(c->gap >= bruteForceSat(a, b) - 1e-12);
    ++compared;
  }
  INFO("largest |gap - FCL distance| = " << worst);
  CHECK(compared > 100);
}

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
    f[0].push_back(2 * (7 - k));   // bottom cap, outward -z: clockwise seen from above
    f[1].push_back(2 * k + 1);     // top cap, outward +z
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
