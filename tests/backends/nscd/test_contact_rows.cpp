// ContactRows (backends/nscd/contact_rows.hpp): the rows one step's contacts make, their
// Delassus diagonal and gap term, which walls get friction rows, and the solved impulses read back
// in contact order whatever the sweep order.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <vector>

#include "backends/nscd/contact_rows.hpp"

using namespace confpack;
using core::Vec3;

namespace {

constexpr double kDt = 0.01;

/// One unit sphere (d = 1, rho = 1): m = pi/6, I = m d^2 / 10.
nscd::BodyInverseMass unitSphere() {
  const double m = std::numbers::pi / 6.0;
  return {1.0 / m, core::Mat3::Identity() * (10.0 / m)};
}

/// A sphere at `centre` touching a wall or a grain through `point`, `gap` across, normal from a to b.
nscd::ContactGeometry touching(int a, int b, const Vec3& normal, const Vec3& point, double gap) {
  nscd::ContactGeometry c;
  c.a = a;
  c.b = b;
  c.normal = normal;
  c.points.fill(Vec3::Zero());  // Eigen leaves the unused points uninitialised
  c.pointCount = 1;
  c.points[0] = point;
  c.gaps[0] = gap;
  return c;
}

}  // namespace

TEST_CASE("contact rows: a sphere on the floor has W_nn = 1/m, no lever arm and the gap over dt as its bias") {
  const std::vector<nscd::BodyInverseMass> bodies = {unitSphere(), {}};  // the grain, then the static world
  const std::vector<Vec3> positions = {Vec3(1.0, 1.0, 0.5)};
  const std::vector<nscd::ContactGeometry> contacts = {
      touching(0, static_cast<int>(core::WallId::Floor), -Vec3::UnitZ(), Vec3(1.0, 1.0, 0.0), 2e-3)};
  nscd::ContactRows rows;
  rows.build(contacts, positions, bodies, core::BoxDef{}, core::WallMaterial{}, kDt, nscd::NscdSettings{});
  REQUIRE(rows.normalRows().size() == 1);
  CHECK(rows.frictionRows().empty());
  const nscd::NormalRow& row = rows.normalRows()[0];
  CHECK(row.invW == Approx(std::numbers::pi / 6.0).epsilon(1e-14));  // 1 / W_nn = m
  CHECK(row.b == 1);                                                 // the static body
  CHECK(row.axn.norm() < 1e-15);                                     // the normal passes through the centre
  CHECK(row.bias == Approx(2e-3 / kDt).epsilon(1e-14));              // an open gap closes in one step at most
  CHECK(rows.turnsNoBody());
}

TEST_CASE("contact rows: side walls with friction make friction rows, the floor never does") {
  const std::vector<nscd::BodyInverseMass> bodies = {unitSphere(), {}};
  const std::vector<Vec3> positions = {Vec3(1.0, 0.5, 0.5)};
  const std::vector<nscd::ContactGeometry> contacts = {
      touching(0, static_cast<int>(core::WallId::Floor), -Vec3::UnitZ(), Vec3(1.0, 0.5, 0.0), 0.0),
      touching(0, static_cast<int>(core::WallId::SideLow), -Vec3::UnitY(), Vec3(1.0, 0.0, 0.5), 0.0)};
  core::WallMaterial walls;
  walls.friction = 0.3;
  nscd::ContactRows rows;
  rows.build(contacts, positions, bodies, core::BoxDef{}, walls, kDt, nscd::NscdSettings{});
  REQUIRE(rows.normalRows().size() == 1);    // the floor: frictionless
  REQUIRE(rows.frictionRows().size() == 1);  // the side wall: Coulomb with mu_w
  const nscd::FrictionRow& f = rows.frictionRows()[0];
  CHECK(f.mu == 0.3);
  // The tangent basis of a side wall is fixed (x, z) and orthogonal to its normal.
  CHECK(f.t1.dot(f.n) == 0.0);
  CHECK(f.t2.dot(f.n) == 0.0);
  // A tangential impulse at the sphere's surface turns it: W_tt = 1/m + (l x t).I^-1 (l x t), with
  // |l x t| = d/2 for both axes, so the larger eigenvalue is 1/m + 10/(4m) = 3.5/m.
  CHECK(f.invWt == Approx(std::numbers::pi / 6.0 / 3.5).epsilon(1e-12));
  // Its tangential impulse turns the sphere (lever arm d/2 across both tangents); its normal
  // one does not, which is all turnsNoBody() says: the normal solves may leave rotations out.
  CHECK(f.axt1.norm() == Approx(0.5).epsilon(1e-15));
  CHECK(f.axt2.norm() == Approx(0.5).epsilon(1e-15));
  CHECK(rows.turnsNoBody());
  // Without friction the same wall is a frictionless row.
  rows.build(contacts, positions, bodies, core::BoxDef{}, core::WallMaterial{}, kDt, nscd::NscdSettings{});
  CHECK(rows.normalRows().size() == 2);
  CHECK(rows.frictionRows().empty());
}

TEST_CASE("contact rows: impulses solved in sweep order read back by contact, from the lowest point up") {
  // A column of three spheres on the floor, its contacts listed top first: the sweep runs bottom up.
  std::vector<nscd::BodyInverseMass> bodies(4, unitSphere());
  bodies.back() = {};
  const std::vector<Vec3> positions = {Vec3(1, 1, 0.5), Vec3(1, 1, 1.5), Vec3(1, 1, 2.5)};
  const std::vector<nscd::ContactGeometry> contacts = {
      touching(1, 2, Vec3::UnitZ(), Vec3(1, 1, 2.0), 0.0),  // contact 0: the highest
      touching(0, 1, Vec3::UnitZ(), Vec3(1, 1, 1.0), 0.0),  // contact 1
      touching(0, static_cast<int>(core::WallId::Floor), -Vec3::UnitZ(), Vec3(1, 1, 0.0), 0.0)};  // contact 2
  nscd::ContactRows rows;
  rows.build(contacts, positions, bodies, core::BoxDef{}, core::WallMaterial{}, kDt, nscd::NscdSettings{});
  REQUIRE(rows.normalRows().size() == 3);
  for (std::size_t k = 1; k < 3; ++k) CHECK(rows.normalRows()[k - 1].z < rows.normalRows()[k].z);
  // Store each row's height as its impulse: contact c must read the height of its own point.
  rows.storeNormalImpulses([&](std::size_t k) { return rows.normalRows()[k].z; });
  CHECK(rows.normalImpulse(0, 0) == 2.0);
  CHECK(rows.normalImpulse(1, 0) == 1.0);
  CHECK(rows.normalImpulse(2, 0) == 0.0);
  std::vector<nscd::CachedContact> cached;
  rows.exportImpulses(contacts, cached);
  REQUIRE(cached.size() == 3);
  CHECK(cached[0].normal[0] == 2.0);
  CHECK(cached[2].normal[0] == 0.0);
}
