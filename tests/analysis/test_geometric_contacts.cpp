// Contacts found from geometry alone (analysis/geometric_contacts.hpp) and their types, for
// hand-placed pinacoids.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/coordination.hpp"
#include "analysis/geometric_contacts.hpp"
#include "core/box.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::pinacoid;

namespace {
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
    p.grains.push_back(pinacoid(1.0, core::Vec3(3, 3, e), core::Quat::Identity()));
    CHECK(onlyType(p, true) == core::ContactType::Double);
  }
  SECTION("trapezoid on the floor: face-face, triple") {
    // The face with normal (0, 1, 1)/sqrt 2 turned to -z; its plane is at sqrt(2)/4 from the centre.
    const core::Quat q(Eigen::AngleAxisd(-0.75 * std::numbers::pi, core::Vec3::UnitX()));
    p.grains.push_back(pinacoid(1.0, core::Vec3(3, 3, std::sqrt(2.0) / 4), q));
    CHECK(onlyType(p, true) == core::ContactType::Triple);
  }
  SECTION("crossed ridges: edge-edge, simple") {
    p.grains.push_back(pinacoid(1.0, core::Vec3(3, 3, 2.0), core::Quat::Identity()));
    p.grains.push_back(pinacoid(1.0, core::Vec3(3, 3, 3.0),
                                core::Quat(Eigen::AngleAxisd(0.5 * std::numbers::pi, core::Vec3::UnitZ()))));
    CHECK(onlyType(p, false) == core::ContactType::Simple);
  }
  SECTION("face on the opposite face of a copy: face-face, triple") {
    // Pinacoids are centrally symmetric: a copy translated by 2 o n has its face -n on the plane of
    // the face n of the first one (o the face offset).
    const core::Grain a = pinacoid(1.0, core::Vec3(3, 3, 3), core::Quat::Identity());
    const core::ConvexPolyhedron poly = a.polyhedron();
    const core::Vec3 n = poly.faceNormals()[0];
    p.grains.push_back(a);
    p.grains.push_back(pinacoid(1.0, a.position + 2 * poly.faceOffsets()[0] * n, core::Quat::Identity()));
    CHECK(onlyType(p, false) == core::ContactType::Triple);
    // Hyperstaticity of a 2-grain "packing" with one triple contact each: 3 - 12.
    const auto counted = analysis::forceCarryingContacts(p, analysis::geometricContacts(p), true);
    const auto r = analysis::coordination(p, analysis::BulkRegion{8.0, 0.0, 8.0}, counted, true);
    REQUIRE(r.hyperstaticity.has_value());
    CHECK(*r.hyperstaticity == Approx(3.0 - 12.0));
  }
}
