// Plausibility of a packing (analysis/plausibility.hpp): each reason on a hand-made packing that
// has it and only it, and the limits on both sides.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "analysis/plausibility.hpp"
#include "core/packing_io.hpp"
#include "tests/support/lattices.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::pinacoid;
using confpack::testing::sphere;

namespace {

std::string reasonOf(const core::Packing& p) {
  const auto why = analysis::implausibility(p);
  return why ? *why : std::string("plausible");
}

/// Two unit spheres side by side on the floor, centres `distance` apart, between walls 4 apart.
core::Packing pair(double distance) {
  core::Packing p;
  p.box.lengthX = 6.0;
  p.box.width = 4.0;
  p.box.height = 3.0;
  p.grains = {sphere(1.0, core::Vec3(2.0, 2.0, 0.5)), sphere(1.0, core::Vec3(2.0 + distance, 2.0, 0.5))};
  return p;
}

core::Contact contactAt(int a, int b, const core::Vec3& point, const core::Vec3& normal) {
  core::Contact c;
  c.a = a;
  c.b = b;
  c.normal = normal;
  c.points.push_back({point, 0.5, core::Vec3::Zero(), 0.0});
  return c;
}

}  // namespace

TEST_CASE("touching spheres, with or without their contacts, are plausible", "[analysis][plausibility]") {
  core::Packing lattice = testing::simpleCubic(4, 4, 3);  // phi = pi/6, every neighbour touching
  CHECK(reasonOf(lattice) == "plausible");
  core::Packing touching = pair(1.0);
  touching.contacts = std::vector<core::Contact>{
      contactAt(0, 1, core::Vec3(2.5, 2.0, 0.5), core::Vec3::UnitX()),
      contactAt(0, static_cast<int>(core::WallId::Floor), core::Vec3(2.0, 2.0, 0.0), -core::Vec3::UnitZ())};
  CHECK(reasonOf(touching) == "plausible");
}

TEST_CASE("a grain larger than the box is implausible", "[analysis][plausibility]") {
  core::Packing p;
  p.box.lengthX = 5.0;
  p.box.width = 5.0;
  p.grains = {sphere(100.0, core::Vec3(2.5, 2.5, 50.0))};
  CHECK(reasonOf(p) == "grain 0 (size 100) is larger than the box's period L_x (5)");
  p.box.lengthX = 200.0;
  CHECK(reasonOf(p) == "grain 0 (size 100) is larger than the box's width W (5)");
  p.box.periodicY = true;
  CHECK(reasonOf(p) == "grain 0 (size 100) is larger than the box's period along y (5)");
  p.box.width = 200.0;
  CHECK(reasonOf(p) == "grain 0 (size 100) is larger than the box's height h (16)");
}

TEST_CASE("grains doubled in size fill more than the box: phi > 1", "[analysis][plausibility]") {
  core::Packing p = testing::simpleCubic(4, 4, 3);
  p.box.height = 3.0;
  for (core::Grain& g : p.grains) g.size *= 2.0;
  // 48 spheres of volume 4 pi / 3 in 4 x 4 x (2.5 + 1), up to the top of the highest: phi = 3.590.
  CHECK_THAT(reasonOf(p), Catch::Contains("phi = 3.59 > 1"));
}

TEST_CASE("an overlap deeper than 0.05 of the smaller grain is implausible, grains or walls",
          "[analysis][plausibility]") {
  CHECK(reasonOf(pair(0.96)) == "plausible");  // 0.04 d
  CHECK_THAT(reasonOf(pair(0.94)), Catch::StartsWith("grain 0 and grain 1 overlap by 0.06 "));
  core::Packing sunk = pair(2.0);
  sunk.grains[1].position.z() = 0.44;  // 0.06 d into the floor
  CHECK_THAT(reasonOf(sunk), Catch::StartsWith("grain 1 and the floor overlap by 0.06 "));
  sunk.grains[1].position.z() = 0.46;
  CHECK(reasonOf(sunk) == "plausible");
  // Pinacoids by the exact narrow phase: a unit pinacoid's ridge (its half-height E/2 = 0.5
  // above the centre) pushed 0.1 into the floor.
  core::Packing pin;
  pin.box.lengthX = 6.0;
  pin.box.width = 6.0;
  pin.grains = {pinacoid(1.0, core::Vec3(3.0, 3.0, 0.4))};
  CHECK_THAT(reasonOf(pin), Catch::StartsWith("grain 0 and the floor overlap by 0.1 "));
  pin.grains[0].position.z() = 0.5;
  CHECK(reasonOf(pin) == "plausible");
}

TEST_CASE("grains with the same centre are the deepest overlap there is, spheres or pinacoids",
          "[analysis][plausibility]") {
  // The failure this guards against: at a centre distance of 0 the pair had no normal and was dropped, so 91
  // spheres in one place passed as a packing without overlap, while 1e-9 apart they were refused.
  CHECK_THAT(reasonOf(pair(0.0)), Catch::StartsWith("grain 0 and grain 1 overlap by 1 "));
  CHECK_THAT(reasonOf(pair(1e-9)), Catch::StartsWith("grain 0 and grain 1 overlap by 1 "));
  core::Packing many = pair(0.0);
  many.grains.assign(91, sphere(1.0, core::Vec3(1.0, 1.0, 1.0)));
  many.box.lengthX = many.box.width = 6.0;
  many.box.height = 6.0;
  CHECK_THAT(reasonOf(many), Catch::StartsWith("grain 0 and grain 1 overlap by 1 "));
  core::Packing pin;
  pin.box.lengthX = 6.0;
  pin.box.width = 6.0;
  pin.grains = {pinacoid(1.0, core::Vec3(3.0, 3.0, 1.0)), pinacoid(1.0, core::Vec3(3.0, 3.0, 1.0))};
  CHECK_THAT(reasonOf(pin), Catch::StartsWith("grain 0 and grain 1 overlap by "));
  CHECK_THROWS_WITH(analysis::checkPlausible(many, "one-place.json", false),
                    Catch::StartsWith("one-place.json: implausible packing: grain 0 and grain 1 overlap by 1 "));
  CHECK_NOTHROW(analysis::checkPlausible(many, "one-place.json", true));
}

TEST_CASE("a contact point far from its grains is implausible", "[analysis][plausibility]") {
  // Grains 3 d apart, centre to centre, with a contact between them at grain 0's surface.
  core::Packing p = pair(3.0);
  p.contacts = std::vector<core::Contact>{contactAt(0, 1, core::Vec3(2.5, 2.0, 0.5), core::Vec3::UnitX())};
  CHECK_THAT(reasonOf(p), Catch::StartsWith("contacts[0] has a point 2 beyond the bounding sphere of grain 1"));
  // 0.1 d beyond the surface is the limit.
  p.grains[1].position.x() = 3.09;
  CHECK(reasonOf(p) == "plausible");
  p.grains[1].position.x() = 3.11;
  CHECK_THAT(reasonOf(p), Catch::Contains("beyond the bounding sphere of grain 1"));
  // A floor contact whose point is a grain's height above the floor.
  core::Packing wall = pair(1.0);
  wall.contacts = std::vector<core::Contact>{
      contactAt(0, static_cast<int>(core::WallId::Floor), core::Vec3(2.0, 2.0, 0.5), -core::Vec3::UnitZ())};
  CHECK_THAT(reasonOf(wall), Catch::StartsWith("contacts[0] has a point 0.5 away from the floor"));
}

TEST_CASE("a packing mixing spheres and pinacoids is refused naming the file and the grain, even if allowed") {
  // Issue 23, failure 8: analyze refused it from inside the analysis, without the file's name.
  confpack::core::Packing p;
  p.box.lengthX = p.box.width = 5.0;
  for (int i = 0; i < 3; ++i) {
    confpack::core::Grain g;
    g.position = confpack::core::Vec3(1.0 + i, 1.0, 0.5);
    p.grains.push_back(g);
  }
  CHECK_NOTHROW(confpack::analysis::checkPlausible(p, "mono.json", false));
  p.grains[2].shape = confpack::core::ShapeKind::Pinacoid;
  const char* message =
      "mixed.json: grains[2].shape: pinacoid, but grains[0] is a sphere: a packing mixing spheres and pinacoids is "
      "not supported";
  CHECK_THROWS_WITH(confpack::analysis::checkPlausible(p, "mixed.json", false), message);
  CHECK_THROWS_WITH(confpack::analysis::checkPlausible(p, "mixed.json", true), message);
}

TEST_CASE("the plausibility fuzz seeds: geometric edge cases at 0 and 1e-15 get their verdicts",
          "[analysis][plausibility]") {
  // The seed corpus of fuzz_plausibility (fuzz/corpus/plausibility/), read as analyze reads it, so
  // that the seeds cannot go stale and each edge case has its verdict.
  const std::string dir = std::string(CONFPACK_SOURCE_DIR) + "/fuzz/corpus/plausibility/";
  const std::pair<const char*, const char*> verdicts[] = {
      {"coincident_spheres.json", "grain 0 and grain 1 overlap by 1 "},
      {"coincident_pinacoids.json", "grain 0 and grain 1 overlap by "},
      {"nested_spheres.json", "grain 0 and grain 1 overlap by "},
      {"coincident_across_period.json", "grain 0 and grain 1 overlap by 1 "},
      {"touching_1e-15.json", "plausible"},
      {"outside_box_1e-15.json", "plausible"},
  };
  for (const auto& [file, verdict] : verdicts) {
    INFO(file);
    CHECK_THAT(reasonOf(core::readPacking(dir + file)), Catch::StartsWith(verdict));
  }
}
