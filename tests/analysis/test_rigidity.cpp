// Rigidity of frictionless sphere networks (analysis/rigidity.hpp; docs/model.md, "Isostaticity"):
// self-stress states and mechanisms counted exactly on networks whose rank is known by hand.
#include <catch2/catch.hpp>
#include <vector>

#include "analysis/coordination.hpp"
#include "analysis/geometric_contacts.hpp"
#include "analysis/rigidity.hpp"
#include "tests/support/lattices.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::simpleCubic;
using confpack::testing::sphere;

namespace {
// A box 4 d_L long (periodic along x) and `width` wide, between frictionless walls, holding `grains`.
core::Packing packingOf(double width, std::vector<core::Grain> grains) {
  core::Packing p;
  p.box.lengthX = 4.0;
  p.box.width = width;
  p.grains = std::move(grains);
  return p;
}

std::optional<analysis::Rigidity> geometricRigidity(const core::Packing& p, std::string* whyNot = nullptr) {
  return analysis::contactRigidity(p, analysis::forceCarryingContacts(p, analysis::geometricContacts(p), true), whyNot);
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
  CHECK(r->selfStresses() == nz * (nx + ny));
  CHECK(r->mechanisms() == nz * (nx + ny));
  // The rings are all between grains; the floor only holds the columns up.
  CHECK(r->selfStressesBetweenGrains() == nz * (nx + ny));
  CHECK(r->rank == 3 * nx * ny * nz - nz * (nx + ny));
}

TEST_CASE("a bead column is isostatic, each bead free to glide sideways", "[analysis][rigidity]") {
  // Five beads on the floor, each on the one below: 5 vertical contacts fix the 5 heights, and
  // nothing holds the 10 horizontal motions on frictionless contacts.
  std::vector<core::Grain> column;
  for (int k = 0; k < 5; ++k) column.push_back(sphere(1.0, core::Vec3(2.0, 2.0, 0.5 + k)));
  const core::Packing p = packingOf(4.0, column);
  const auto r = geometricRigidity(p);
  REQUIRE(r.has_value());
  CHECK(r->contacts == 5);
  CHECK(r->selfStresses() == 0);
  CHECK(r->mechanisms() == 10);
}

TEST_CASE("two beads wedged between the side walls carry one self-stress", "[analysis][rigidity]") {
  // W = 2 d: wall, bead, bead, wall touch along y, three contacts on two motions; both beads on the
  // floor. Rank 4 of 5 contacts and 6 motions: h = 1 (the row squeezed), k = 2 (gliding along x).
  const core::Packing p =
      packingOf(2.0, {sphere(1.0, core::Vec3(2.0, 0.5, 0.5)), sphere(1.0, core::Vec3(2.0, 1.5, 0.5))});
  const auto r = geometricRigidity(p);
  REQUIRE(r.has_value());
  CHECK(r->contacts == 5);
  CHECK(r->selfStresses() == 1);
  CHECK(r->mechanisms() == 2);
  // It runs through the walls: between the grains alone, no self-stress.
  CHECK(r->selfStressesBetweenGrains() == 0);
}

TEST_CASE("rigidity is not defined between frictional walls, and says why", "[analysis][rigidity]") {
  core::Packing p = simpleCubic(4, 4, 2);
  std::string why;
  p.walls.friction = 0.5;
  CHECK_FALSE(geometricRigidity(p, &why).has_value());
  CHECK(why == "defined between frictionless walls only");
}

namespace {
// A face contact as a backend reports it: four points of a square in the contact plane (only the
// points and the grain's centroid enter the count, not the grain's shape).
core::Contact faceContact(int a, int b, const core::Vec3& normal, const core::Vec3& centre, const core::Vec3& u,
                          const core::Vec3& v) {
  core::Contact c;
  c.a = a;
  c.b = b;
  c.type = core::ContactType::Triple;
  c.normal = normal;
  for (const double su : {-0.4, 0.4})
    for (const double sv : {-0.4, 0.4}) {
      core::ContactPoint point;
      point.position = centre + su * u + sv * v;
      point.normalForce = 1.0;
      c.points.push_back(point);
    }
  return c;
}
}  // namespace

TEST_CASE(
    "a pinacoid's face contact of four points is three constraints: a block on the floor, wedged "
    "between the walls",
    "[analysis][rigidity]") {
  // A grain at the floor's centre, its contact a square of four points: 3 constraints (z and the
  // two tilts), not 4, so no self-stress; free: x, y and the turn about z.
  const core::Packing p = packingOf(1.0, {confpack::testing::pinacoid(1.0, core::Vec3(2.0, 0.5, 0.5))});
  const core::Vec3 x = core::Vec3::UnitX(), y = core::Vec3::UnitY(), z = core::Vec3::UnitZ();
  const int floor = static_cast<int>(core::WallId::Floor);
  std::vector<core::Contact> contacts = {faceContact(0, floor, -z, core::Vec3(2.0, 0.5, 0.0), x, y)};
  auto r = analysis::contactRigidity(p, analysis::forceCarryingContacts(p, contacts, false));
  REQUIRE(r.has_value());
  CHECK(r->contacts == 1);
  CHECK(r->constraints == 3);
  CHECK(r->degreesOfFreedom == 6);
  CHECK(r->selfStresses() == 0);
  CHECK(r->mechanisms() == 3);
  // Faces on both side walls too (W = its width): each wall fixes y and the two tilts out of its
  // plane (about x and z). With the floor that is y, z and all three turns: rank 5 of 9
  // constraints, h = 4 (the grain squeezed between the walls, and twisted against them), k = 1
  // (sliding along x).
  contacts.push_back(faceContact(0, static_cast<int>(core::WallId::SideLow), -y, core::Vec3(2.0, 0.0, 0.5), x, z));
  contacts.push_back(faceContact(0, static_cast<int>(core::WallId::SideHigh), y, core::Vec3(2.0, 1.0, 0.5), x, z));
  r = analysis::contactRigidity(p, analysis::forceCarryingContacts(p, contacts, false));
  REQUIRE(r.has_value());
  CHECK(r->constraints == 9);
  CHECK(r->rank == 5);
  CHECK(r->selfStresses() == 4);
  CHECK(r->mechanisms() == 1);
}

TEST_CASE("a pinacoid's edge contact is two constraints and a vertex contact one", "[analysis][rigidity]") {
  const core::Packing p = packingOf(4.0, {confpack::testing::pinacoid(1.0, core::Vec3(2.0, 2.0, 0.5))});
  const int floor = static_cast<int>(core::WallId::Floor);
  core::Contact edge;
  edge.a = 0;
  edge.b = floor;
  edge.normal = -core::Vec3::UnitZ();
  // An edge on the floor, reported as three collinear points: two constraints (z, the tilt across it).
  for (const double s : {-0.4, 0.0, 0.4})
    edge.points.push_back({core::Vec3(2.0 + s, 2.0, 0.0), 1.0, core::Vec3::Zero(), 0.0});
  auto r = analysis::contactRigidity(p, analysis::forceCarryingContacts(p, {edge}, false));
  REQUIRE(r.has_value());
  CHECK(r->constraints == 2);
  CHECK(r->selfStresses() == 0);
  CHECK(r->mechanisms() == 4);
  core::Contact vertex = edge;
  vertex.points.resize(1);
  r = analysis::contactRigidity(p, analysis::forceCarryingContacts(p, {vertex}, false));
  REQUIRE(r.has_value());
  CHECK(r->constraints == 1);
  CHECK(r->mechanisms() == 5);
}
