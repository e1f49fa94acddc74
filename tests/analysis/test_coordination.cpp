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

TEST_CASE("contact types by a tolerance band: a face tilted by 3 degrees is triple in the band, not exactly",
          "[analysis][coordination]") {
  using confpack::testing::pinacoid;
  core::Packing p;
  p.box.lengthX = 6.0;
  p.box.width = 4.0;
  p.box.periodicY = true;
  // b's bottom trapezoid on a's top trapezoid (plane y + z = 1/2 in a's frame, L = G = E = 1), b
  // then turned by 3 degrees about the x axis through the middle of the contact.
  const core::Vec3 xa(3.0, 2.0, 5.0);
  const core::Vec3 pivot = xa + core::Vec3(0.0, 0.25, 0.25);
  const core::Quat tilt(Eigen::AngleAxisd(3.0 * std::numbers::pi / 180.0, core::Vec3::UnitX()));
  p.grains = {pinacoid(1.0, xa), pinacoid(1.0, pivot + tilt * (xa + core::Vec3(0.0, 0.5, 0.5) - pivot), tilt)};
  const auto counted = analysis::forceCarryingContacts(p, analysis::geometricContacts(p), true);
  REQUIRE(counted.size() == 1);
  CHECK(counted[0].type != core::ContactType::Triple);
  const auto band = analysis::bandTypedContacts(p, counted, 0.1);
  REQUIRE(band.size() == 1);
  CHECK(band[0].type == core::ContactType::Triple);
  // The same contacts counted: one triple contact per grain in the band, none exactly.
  const analysis::BulkRegion region{10.0, 3.0, 7.0};
  const analysis::Coordination exact = analysis::coordination(p, region, counted, true);
  const analysis::Coordination byBand = analysis::coordination(p, region, band, true);
  CHECK(exact.z == 1.0);
  CHECK(byBand.z == 1.0);
  CHECK(exact.zTriple == 0.0);
  CHECK(byBand.zTriple == 1.0);
  for (double b : {0.0, -0.1, 0.51, std::nan("")})
    CHECK_THROWS_WITH(analysis::bandTypedContacts(p, counted, b), Catch::Contains("type_band"));
}

TEST_CASE("contact types by a tolerance band: a pinacoid's face a few degrees off the floor is triple",
          "[analysis][coordination]") {
  using confpack::testing::pinacoid;
  core::Packing p;
  p.box.lengthX = 6.0;
  p.box.width = 4.0;
  p.box.periodicY = true;
  // Upside down on its top ridge (vertices (+-l, 0, 1/2) in the body frame): a Double wall contact
  // either way. Its bottom trapezoid y < 0 (normal (0, -1, -1)/sqrt 2) turned down onto the floor
  // and tilted by 3 degrees: Triple in the band only.
  const core::Quat flip(Eigen::AngleAxisd(std::numbers::pi, core::Vec3::UnitX()));
  const core::Quat down = core::Quat::FromTwoVectors(core::Vec3(0, -1, -1).normalized(), -core::Vec3::UnitZ());
  const core::Quat tilt(Eigen::AngleAxisd(3.0 * std::numbers::pi / 180.0, core::Vec3::UnitX()));
  p.grains = {pinacoid(1.0, core::Vec3(1.5, 2.0, 0.5), flip), pinacoid(1.0, core::Vec3(4.5, 2.0, 2.0), tilt * down)};
  p.grains[1] = confpack::testing::withBottomAt(p.grains[1], 0.0);
  const auto counted = analysis::forceCarryingContacts(p, analysis::geometricContacts(p), true);
  REQUIRE(counted.size() == 2);
  const auto band = analysis::bandTypedContacts(p, counted, 0.1);
  CHECK(counted[0].type == core::ContactType::Double);
  CHECK(band[0].type == core::ContactType::Double);
  CHECK(counted[1].type != core::ContactType::Triple);
  CHECK(band[1].type == core::ContactType::Triple);
}
