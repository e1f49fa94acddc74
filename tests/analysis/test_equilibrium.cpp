// The equilibrium test and the contact stress (analysis/equilibrium.hpp; docs/model.md,
// "Equilibrium") against exact static forces.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/bulk_region.hpp"
#include "analysis/equilibrium.hpp"
#include "tests/support/lattices.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::column;
using confpack::testing::simpleCubic;

namespace {
// A column of n beads on the floor with the exact static forces: the k-th contact from the top
// carries k m g (the rigid chain: no elastic give).
core::Packing loadedColumn(int n, double d = 1.0) {
  core::Packing p;
  p.box.lengthX = 5.0;
  p.box.width = 5.0;
  p.grains = column(n, 2.5, 2.5, d);
  const double mg = p.grains[0].volume();
  std::vector<core::Contact> contacts;
  core::Contact floor;
  floor.a = 0;
  floor.b = static_cast<int>(core::WallId::Floor);
  floor.normal = -core::Vec3::UnitZ();
  floor.points.push_back({core::Vec3(2.5, 2.5, 0.0), n * mg});
  contacts.push_back(floor);
  for (int k = 0; k + 1 < n; ++k) {
    core::Contact c;
    c.a = k;
    c.b = k + 1;
    c.normal = core::Vec3::UnitZ();
    c.points.push_back({core::Vec3(2.5, 2.5, (k + 1) * d), (n - k - 1) * mg});
    contacts.push_back(c);
  }
  p.contacts = contacts;
  return p;
}

// One sphere of diameter d on the floor of a 3 x 3 box, the floor carrying its weight.
core::Packing sphereOnFloor(double d) {
  core::Packing p;
  p.box.lengthX = 3;
  p.box.width = 3;
  p.grains = column(1, 1.0, 1.0, d);
  core::Contact c;
  c.a = 0;
  c.b = static_cast<int>(core::WallId::Floor);
  c.normal = -core::Vec3::UnitZ();
  c.points.push_back({core::Vec3(1.0, 1.0, 0.0), p.grains[0].volume()});
  p.contacts = std::vector<core::Contact>{c};
  return p;
}
}  // namespace

TEST_CASE("equilibrium of a column with exact forces", "[analysis][equilibrium]") {
  const core::Vec3 g(0, 0, -1);
  core::Packing p = loadedColumn(8);
  const auto rep = analysis::equilibrium(p, {}, g, 1.0);
  CHECK(rep.reached);
  CHECK(rep.maxForceRatio < 1e-12);
  CHECK(rep.maxMomentRatio < 1e-12);
  CHECK(rep.maxKineticRatio == 0.0);
  // Bulk slab 3 < z < 5 holds beads 3 and 4. Bead i carries, in zz, r ((n-i) + (n-i-1)) m g
  // from its two contacts: 9 + 7 = 16 r m g over V = L_x W 2.
  CHECK(rep.pressureFromBulk);
  const double mg = std::numbers::pi / 6;
  CHECK(rep.pressure == Approx(0.5 * 16 * mg / (3 * 25.0 * 2.0)));
  // A column too low for a bulk: all beads, sum over i of r (2n - 2i - 1) m g = r n^2 m g,
  // over V = L_x W h_free.
  const auto low = analysis::equilibrium(loadedColumn(4), {}, g, 1.0);
  CHECK(low.reached);
  CHECK_FALSE(low.pressureFromBulk);
  CHECK(low.pressure == Approx(0.5 * 16 * mg / (3 * 25.0 * 4.0)));

  SECTION("a wrong force breaks it") {
    (*p.contacts)[3].points[0].normalForce *= 1.01;
    const auto bad = analysis::equilibrium(p, {}, g, 1.0);
    CHECK_FALSE(bad.reached);
    CHECK(bad.maxForceRatio > 1e-2);
    CHECK((bad.worstGrain == 2 || bad.worstGrain == 3));
  }
  SECTION("an off-centre point gives a moment") {
    (*p.contacts)[2].points[0].position.x() += 0.1;
    const auto bad = analysis::equilibrium(p, {}, g, 1.0);
    CHECK_FALSE(bad.reached);
    CHECK(bad.maxForceRatio < 1e-12);
    CHECK(bad.maxMomentRatio > 1e-2);
  }
  SECTION("a moving grain breaks it") {
    std::vector<core::BodyState> states(p.grains.size());
    states[4].velocity = core::Vec3(0, 1e-2, 0);
    const auto bad = analysis::equilibrium(p, states, g, 1.0);
    CHECK_FALSE(bad.reached);
    // E_k = m v^2 / 2 over d^3 P.
    CHECK(bad.maxKineticRatio == Approx(0.5 * mg * 1e-4 / rep.pressure));
    states[4].velocity.setZero();
    states[4].angularVelocity = core::Vec3(0.3, 0, 0);
    const auto spin = analysis::equilibrium(p, states, g, 1.0);
    // I = m d^2 / 10 for a sphere.
    CHECK(spin.maxKineticRatio == Approx(0.5 * 0.1 * mg * 0.09 / rep.pressure));
    std::vector<core::BodyState> wrongSize(3);
    CHECK_THROWS_AS(analysis::equilibrium(p, wrongSize, g, 1.0), std::invalid_argument);
  }
}

TEST_CASE("a single sphere resting on the floor is at equilibrium", "[analysis][equilibrium]") {
  core::Packing p = sphereOnFloor(1.2);
  CHECK(analysis::equilibrium(p, {}, core::Vec3(0, 0, -1), 1.0).reached);
  // A rattler (no contact) in the same box fails: gravity is unbalanced.
  core::Grain loose = p.grains[0];
  loose.position = core::Vec3(2.5, 2.5, 0.9);
  p.grains.push_back(loose);
  const auto rep = analysis::equilibrium(p, {}, core::Vec3(0, 0, -1), 1.0);
  CHECK_FALSE(rep.reached);
  CHECK(rep.worstGrain == 1);
  // No contact list at all is refused.
  p.contacts.reset();
  CHECK_THROWS_AS(analysis::equilibrium(p, {}, core::Vec3(0, 0, -1), 1.0), std::invalid_argument);
}

TEST_CASE("a spinning sphere is not at rest, but its spin is no settling motion", "[analysis][equilibrium]") {
  // P from the whole-pile fallback (the pile is too low for a bulk region).
  core::Packing p = sphereOnFloor(1.0);
  const double m = p.grains[0].volume(), inertia = 0.1 * m;  // I = m d^2 / 10
  core::BodyState s;
  s.angularVelocity = core::Vec3(0.3, 0.0, 0.4);  // |omega| = 0.5
  const auto spinning = analysis::equilibrium(p, {s}, core::Vec3(0, 0, -1), 1.0);
  const double scale = 1.0 / spinning.pressure;  // d = 1
  CHECK_FALSE(spinning.reached);
  CHECK(spinning.maxKineticRatio == Approx(0.5 * inertia * 0.25 * scale).epsilon(1e-12));
  CHECK(spinning.meanKineticRatio == Approx(0.5 * inertia * 0.25 * scale).epsilon(1e-12));
  CHECK(spinning.meanSettlingKineticRatio == 0.0);
  // Sliding as well: the settling motion is the translation alone.
  s.velocity = core::Vec3(0.2, 0.0, 0.0);
  const auto sliding = analysis::equilibrium(p, {s}, core::Vec3(0, 0, -1), 1.0);
  CHECK(sliding.meanKineticRatio == Approx((0.5 * inertia * 0.25 + 0.5 * m * 0.04) * scale).epsilon(1e-12));
  CHECK(sliding.meanSettlingKineticRatio == Approx(0.5 * m * 0.04 * scale).epsilon(1e-12));
  // A pinacoid's spin moves its boundary: it counts.
  p.grains[0] = testing::withBottomAt(testing::pinacoid(1.0, core::Vec3(1.0, 1.0, 0.0)), 0.0);
  s.velocity = core::Vec3::Zero();
  const auto pinacoid = analysis::equilibrium(p, {s}, core::Vec3(0, 0, -1), 1.0);
  CHECK(pinacoid.meanSettlingKineticRatio > 0.0);
  CHECK(pinacoid.meanSettlingKineticRatio == pinacoid.meanKineticRatio);
}

TEST_CASE("contact stress of a periodic pair uses the minimum image", "[analysis][equilibrium]") {
  // Two spheres touching across the x boundary, squeezed by a force f: sigma_xx = f d / V.
  core::Packing p;
  p.box.lengthX = 4;
  p.box.width = 2;
  p.box.periodicY = true;
  p.grains = column(1, 3.75, 1.0, 0.5);
  p.grains.push_back(p.grains[0]);
  p.grains[0].position.z() = 5.0;
  p.grains[1].position = core::Vec3(0.25, 1.0, 5.0);
  core::Contact c;
  c.a = 0;
  c.b = 1;
  c.normal = core::Vec3::UnitX();
  c.points.push_back({core::Vec3(4.0, 1.0, 5.0), 2.0});
  p.contacts = std::vector<core::Contact>{c};
  analysis::BulkRegion region{10.0, 3.0, 7.0};
  bool bulk = false;
  const core::Mat3 s = analysis::contactStress(p, region, &bulk);
  CHECK(bulk);
  CHECK(s(0, 0) == Approx(2.0 * 0.5 / (4 * 2 * 4.0)));
  CHECK(std::abs(s(1, 1)) < 1e-15);
  CHECK(std::abs(s(0, 2)) < 1e-15);
}
