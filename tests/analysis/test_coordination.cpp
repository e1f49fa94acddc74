// Coordination (analysis/coordination.hpp; docs/model.md, "Coordination number"): lattice values
// of Z and the force-carrying contacts counted at a force threshold, merged per pair.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/coordination.hpp"
#include "analysis/geometric_contacts.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;
using confpack::testing::faceCentredCubic;
using confpack::testing::simpleCubic;

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

