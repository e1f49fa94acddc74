// Coordination, geometric contacts, contact types, fabric, nematic order and homogeneity
// (docs/model.md, "Homogeneity", "Order", "Coordination number") against exact lattice values and
// known distributions.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/coordination.hpp"
#include "analysis/fabric.hpp"
#include "analysis/geometric_contacts.hpp"
#include "analysis/homogeneity.hpp"
#include "analysis/nematic.hpp"
#include "core/random.hpp"
#include "lattices.hpp"

using namespace confpack;
using analysis::testing::faceCentredCubic;
using analysis::testing::simpleCubic;

namespace {
analysis::Coordination geometricCoordination(const core::Packing& p, const analysis::BulkRegion& region) {
  const auto contacts = analysis::geometricContacts(p);
  const auto counted = analysis::forceCarryingContacts(p, contacts, true);
  return analysis::coordination(p, region, counted, true);
}
}  // namespace

TEST_CASE("simple cubic lattice has Z = 6, fcc Z = 12", "[analysis][coordination]") {
  const core::Packing sc = simpleCubic(5, 5, 10);
  const auto r = geometricCoordination(sc, analysis::bulkRegion(sc));
  CHECK(r.bulkGrains == 5 * 5 * 4);
  CHECK(r.z == Approx(6.0));
  CHECK(r.zSimple == Approx(6.0));
  CHECK(r.rattlerFraction == 0.0);
  CHECK_FALSE(r.hyperstaticity.has_value());
  // Floor contacts: the 25 spheres of the first layer.
  CHECK(r.wallContacts == 25);
  for (std::size_t k = 0; k < r.profile.z.size(); ++k)
    if (r.profile.grains[k] > 0) CHECK(r.profile.z[k] == Approx(6.0));

  const core::Packing fcc = faceCentredCubic(4, 6);
  const auto f = geometricCoordination(fcc, analysis::BulkRegion{10.0, 2.0, 6.0});
  CHECK(f.bulkGrains > 100);
  CHECK(f.z == Approx(12.0));

  // A loose lattice (gap 1e-3) has no contact at the default tolerance: all rattlers.
  core::Packing loose = simpleCubic(5, 5, 10);
  for (auto& g : loose.grains) g.size = 0.999;
  for (const auto& c : analysis::geometricContacts(loose)) CHECK(core::isWall(c.b));
}

TEST_CASE("force threshold and merged contacts", "[analysis][coordination]") {
  core::Packing p = simpleCubic(4, 4, 10);
  const analysis::BulkRegion region = analysis::bulkRegion(p);
  std::vector<core::Contact> contacts = analysis::geometricContacts(p);
  // Give every contact force 1 except the contacts of grain 90, which get 1e-6 (below 1e-3 mean).
  int touched = 0;
  for (auto& c : contacts)
    for (auto& pt : c.points) pt.normalForce = (c.a == 90 || c.b == 90) ? 1e-6 : 1.0;
  for (const auto& c : contacts) touched += (c.a == 90 || c.b == 90) && !core::isWall(c.b);
  REQUIRE(touched == 6);
  // A duplicated report of one pair must not count twice.
  contacts.push_back(contacts[0]);
  const auto counted = analysis::forceCarryingContacts(p, contacts, false);
  const auto r = analysis::coordination(p, region, counted, false);
  REQUIRE(p.grains[90].position.z() == Approx(5.5));
  CHECK(r.rattlerFraction == Approx(1.0 / r.bulkGrains));
  CHECK(r.z == Approx((6.0 * r.bulkGrains - 12.0) / r.bulkGrains));
  CHECK(r.zNonRattler == Approx((6.0 * (r.bulkGrains - 1) - 6.0) / (r.bulkGrains - 1)));
  // Bad contact indices are refused with a message.
  core::Contact bad;
  bad.a = 0;
  bad.b = 999;
  contacts.push_back(bad);
  CHECK_THROWS_AS(analysis::forceCarryingContacts(p, contacts, false), std::invalid_argument);
}

namespace {
core::Grain pinacoid(const core::Vec3& x, const core::Quat& q) {
  core::Grain g;
  g.shape = core::ShapeKind::Pinacoid;
  g.size = 1.0;
  g.position = x;
  g.orientation = q;
  return g;
}
core::ContactType onlyType(const core::Packing& p, bool wall) {
  const auto counted = analysis::forceCarryingContacts(p, analysis::geometricContacts(p), true);
  std::vector<core::ContactType> types;
  for (const auto& c : counted)
    if (core::isWall(c.b) == wall) types.push_back(c.type);
  REQUIRE(types.size() == 1);
  return types[0];
}
}  // namespace

TEST_CASE("contact types of hand-placed pinacoids", "[analysis][coordination][pinacoid]") {
  core::Packing p;
  p.box.lengthX = 6;
  p.box.width = 6;
  const double e = 0.5;  // E/2 for L = G = E = 1
  SECTION("ridge on the floor: edge-face, double") {
    p.grains.push_back(pinacoid(core::Vec3(3, 3, e), core::Quat::Identity()));
    CHECK(onlyType(p, true) == core::ContactType::Double);
  }
  SECTION("trapezoid on the floor: face-face, triple") {
    // The face with normal (0, 1, 1)/sqrt 2 turned to -z; its plane is at sqrt(2)/4 from the centre.
    const core::Quat q(Eigen::AngleAxisd(-0.75 * std::numbers::pi, core::Vec3::UnitX()));
    p.grains.push_back(pinacoid(core::Vec3(3, 3, std::sqrt(2.0) / 4), q));
    CHECK(onlyType(p, true) == core::ContactType::Triple);
  }
  SECTION("crossed ridges: edge-edge, simple") {
    p.grains.push_back(pinacoid(core::Vec3(3, 3, 2.0), core::Quat::Identity()));
    p.grains.push_back(
        pinacoid(core::Vec3(3, 3, 3.0), core::Quat(Eigen::AngleAxisd(0.5 * std::numbers::pi, core::Vec3::UnitZ()))));
    CHECK(onlyType(p, false) == core::ContactType::Simple);
  }
  SECTION("face on the opposite face of a copy: face-face, triple") {
    // Pinacoids are centrally symmetric: a copy translated by 2 o n has its face -n on the plane of
    // the face n of the first one (o the face offset).
    const core::Grain a = pinacoid(core::Vec3(3, 3, 3), core::Quat::Identity());
    const core::ConvexPolyhedron poly = a.polyhedron();
    const core::Vec3 n = poly.faceNormals()[0];
    p.grains.push_back(a);
    p.grains.push_back(pinacoid(a.position + 2 * poly.faceOffsets()[0] * n, core::Quat::Identity()));
    CHECK(onlyType(p, false) == core::ContactType::Triple);
    // Hyperstaticity of a 2-grain "packing" with one triple contact each: 3 - 12.
    const auto counted = analysis::forceCarryingContacts(p, analysis::geometricContacts(p), true);
    const auto r = analysis::coordination(p, analysis::BulkRegion{8.0, 0.0, 8.0}, counted, true);
    REQUIRE(r.hyperstaticity.has_value());
    CHECK(*r.hyperstaticity == Approx(3.0 - 12.0));
  }
}

TEST_CASE("fabric anisotropy estimator", "[analysis][fabric]") {
  core::Rng rng(3, core::StreamId::Test);
  auto isotropic = [&]() {
    core::Vec3 v(rng.normal(), rng.normal(), rng.normal());
    return core::Vec3(v.normalized());
  };
  const int n = 40000;
  std::vector<core::Vec3> iso;
  for (int k = 0; k < n; ++k) iso.push_back(isotropic());
  CHECK(std::abs(analysis::fabricOfDirections(iso).anisotropy) < 5.0 / std::sqrt(double(n)) * 2.5);
  CHECK(analysis::fabricOfDirections(iso).tensor.trace() == Approx(1.0));
  // Rejection sampling of P ~ 1 + a (3 cos^2 - 1) about z.
  for (double a : {0.2, 0.5}) {
    std::vector<core::Vec3> dirs;
    while (static_cast<int>(dirs.size()) < n) {
      const core::Vec3 v = isotropic();
      if (rng.uniform() * (1 + 2 * a) < 1 + a * (3 * v.z() * v.z() - 1)) dirs.push_back(v);
    }
    const auto f = analysis::fabricOfDirections(dirs);
    CHECK(f.anisotropy == Approx(a).margin(0.03));
    CHECK(std::abs(f.majorAxis.z()) > 0.99);
  }
  // Three orthogonal pairs: exactly isotropic, a = 0.
  CHECK(analysis::fabricOfDirections({core::Vec3::UnitX(), core::Vec3::UnitY(), core::Vec3::UnitZ()}).anisotropy ==
        Approx(0.0).margin(1e-14));
}

TEST_CASE("fabric of a simple cubic lattice", "[analysis][fabric]") {
  const core::Packing sc = simpleCubic(4, 4, 10);
  const analysis::BulkRegion region = analysis::bulkRegion(sc);
  const auto counted = analysis::forceCarryingContacts(sc, analysis::geometricContacts(sc), true);
  const auto f = analysis::fabric(sc, region, counted);
  // F = I/3 exactly for the six lattice directions.
  CHECK(f.anisotropy == Approx(0.0).margin(1e-12));
  // Normals: one third vertical (|n_z| = 1 in the last bin), two thirds horizontal (first bin).
  const auto& h = f.orientation[3];
  CHECK(h.count == f.contacts);
  CHECK(h.cosTheta.back() == Approx(10.0 / 3.0));
  CHECK(h.cosTheta.front() == Approx(20.0 / 3.0));
  // Azimuth of the horizontal ones: 0 and 90 degrees only.
  CHECK(h.azimuth[0] + h.azimuth[9] == Approx(18.0));
}

TEST_CASE("nematic order: aligned and random pinacoids", "[analysis][nematic]") {
  std::vector<core::Mat3> aligned(
      50, core::Quat(Eigen::AngleAxisd(0.4, core::Vec3(1, 2, 3).normalized())).toRotationMatrix());
  const auto a = analysis::nematicOrder(aligned);
  CHECK(a.q00 == Approx(1.0));
  core::Rng rng(11, core::StreamId::Test);
  for (int n : {400, 6400}) {
    std::vector<core::Mat3> random;
    for (int k = 0; k < n; ++k) random.push_back(rng.uniformQuaternion().toRotationMatrix());
    const auto r = analysis::nematicOrder(random);
    CHECK(r.q00 > 0.0);
    CHECK(r.q00 < 4.0 / std::sqrt(double(n)));
  }
  // In a packing: boundary layers (within 2 d_L of a wall) and bulk are separate groups.
  core::Packing p;
  p.box.lengthX = 10;
  p.box.width = 10;
  for (int k = 0; k < 20; ++k) {
    core::Grain g;
    g.shape = core::ShapeKind::Pinacoid;
    g.position = core::Vec3(0.5 * k, k % 2 ? 1.0 : 5.0, 5.0);
    g.orientation = k % 2 ? core::Quat::Identity() : rng.uniformQuaternion();
    p.grains.push_back(g);
  }
  const auto nem = analysis::nematic(p, analysis::BulkRegion{10, 3, 7});
  REQUIRE(nem.boundary.has_value());
  REQUIRE(nem.bulk.has_value());
  CHECK(nem.boundary->q00 == Approx(1.0));
  CHECK(nem.boundary->grains == 10);
  CHECK(nem.bulk->q00 < 0.9);
  CHECK_FALSE(analysis::nematic(simpleCubic(3, 3, 8), analysis::BulkRegion{8, 3, 5}).bulk.has_value());
}

TEST_CASE("homogeneity counts large and small grains per layer", "[analysis][homogeneity]") {
  core::Packing p = simpleCubic(4, 4, 8);
  // Make the grains of every second layer small (their centres stay put).
  for (auto& g : p.grains)
    if (static_cast<int>(g.position.z()) % 2 == 1) g.size = 0.5;
  // And in the bulk, the column y in [0, 1) small too.
  for (auto& g : p.grains)
    if (g.position.y() < 1.0) g.size = 0.5;
  const auto h = analysis::homogeneity(p, analysis::bulkRegion(p));
  REQUIRE(h.alongZ.pLarge.size() == 8);
  CHECK(h.alongZ.pLarge[0] == Approx(12.0 / 16.0));
  CHECK(h.alongZ.pSmall[1] == Approx(1.0));
  REQUIRE(h.alongY.pLarge.size() == 4);
  CHECK(h.alongY.pSmall[0] == Approx(1.0));
  // Bulk layers z = 3.5 (large except y column) and 4.5 (small): half of each y-layer is large.
  CHECK(h.alongY.pLarge[2] == Approx(0.5));
  CHECK(h.alongY.large[2] + h.alongY.small[2] == 8);
}
