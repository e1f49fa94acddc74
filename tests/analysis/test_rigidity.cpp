// Rigidity of frictionless sphere networks (analysis/rigidity.hpp; docs/model.md, "Isostaticity"):
// self-stress states and mechanisms counted exactly on networks whose rank is known by hand.
#include <catch2/catch.hpp>

#include "analysis/coordination.hpp"
#include "analysis/geometric_contacts.hpp"
#include "analysis/rigidity.hpp"
#include "tests/support/lattices.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::simpleCubic;
using confpack::testing::sphere;

namespace {
std::optional<analysis::Rigidity> geometricRigidity(const core::Packing& p, std::string* whyNot = nullptr) {
  return analysis::sphereRigidity(p, analysis::forceCarryingContacts(p, analysis::geometricContacts(p), true), whyNot);
}
}  // namespace

TEST_CASE("a simple cubic crystal on the floor: one self-stress and one mechanism per periodic row",
          "[analysis][rigidity]") {
  // Periodic in x and y: each row along x (or y) is a ring of touching spheres whose contacts all
  // push along the row, n contacts on n motions of rank n - 1: one self-stress (the ring squeezed
  // evenly) and one mechanism (the ring sliding along itself). Each column stands on the floor,
  // nz contacts on nz vertical motions: neither. So h = k = nz (nx + ny).
  const int nx = 4, ny = 5, nz = 6;
  const core::Packing p = simpleCubic(nx, ny, nz);
  const auto r = geometricRigidity(p);
  REQUIRE(r.has_value());
  CHECK(r->contacts == 3 * nx * ny * nz);
  CHECK(r->degreesOfFreedom == 3 * nx * ny * nz);
  CHECK(r->selfStresses == nz * (nx + ny));
  CHECK(r->mechanisms == nz * (nx + ny));
  CHECK(r->rank == r->contacts - r->selfStresses);
}

TEST_CASE("a bead column is isostatic, each bead free to glide sideways", "[analysis][rigidity]") {
  // Five beads on the floor, each on the one below: 5 vertical contacts fix the 5 heights, and
  // nothing holds the 10 horizontal motions on frictionless contacts.
  core::Packing p;
  p.box.lengthX = 4.0;
  p.box.width = 4.0;
  for (int k = 0; k < 5; ++k) p.grains.push_back(sphere(1.0, core::Vec3(2.0, 2.0, 0.5 + k)));
  const auto r = geometricRigidity(p);
  REQUIRE(r.has_value());
  CHECK(r->contacts == 5);
  CHECK(r->selfStresses == 0);
  CHECK(r->mechanisms == 10);
}

TEST_CASE("two beads wedged between the side walls carry one self-stress", "[analysis][rigidity]") {
  // W = 2 d: wall, bead, bead, wall touch along y, three contacts on two motions; both beads on the
  // floor. Rank 4 of 5 contacts and 6 motions: h = 1 (the row squeezed), k = 2 (gliding along x).
  core::Packing p;
  p.box.lengthX = 4.0;
  p.box.width = 2.0;
  p.grains = {sphere(1.0, core::Vec3(2.0, 0.5, 0.5)), sphere(1.0, core::Vec3(2.0, 1.5, 0.5))};
  const auto r = geometricRigidity(p);
  REQUIRE(r.has_value());
  CHECK(r->contacts == 5);
  CHECK(r->selfStresses == 1);
  CHECK(r->mechanisms == 2);
}

TEST_CASE("rigidity is not defined for pinacoids nor between frictional walls, and says why", "[analysis][rigidity]") {
  core::Packing p = simpleCubic(4, 4, 2);
  std::string why;
  p.walls.friction = 0.5;
  CHECK_FALSE(geometricRigidity(p, &why).has_value());
  CHECK(why == "defined between frictionless walls only");
  p.walls.friction = 0.0;
  p.grains.push_back(confpack::testing::pinacoid(1.0, core::Vec3(2.0, 2.0, 3.0)));
  CHECK_FALSE(analysis::sphereRigidity(p, {}, &why).has_value());
  CHECK(why == "defined for sphere packings only");
}
