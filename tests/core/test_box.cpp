// BoxDef (core/box.hpp): periodic wrapping and the minimum image, the walls, JSON and validation.
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/box.hpp"

using namespace confpack::core;

TEST_CASE("wrapping a tiny negative coordinate stays inside the period") {
  BoxDef box;
  box.lengthX = 20.0;
  box.periodicY = true;
  for (double x : {-1e-16, -1.7e-15, -0.0, 20.0, 40.0, -20.0}) {
    const Vec3 w = box.wrap(Vec3(x, x / 2, 1.0));
    CHECK(w.x() >= 0.0);
    CHECK(w.x() < box.lengthX);
    CHECK(w.y() >= 0.0);
    CHECK(w.y() < box.width);
  }
}

TEST_CASE("the minimum image is the shortest periodic copy of a separation") {
  // Brute force over the images d + (i L_x, j W, 0): the minimum image is one of them and none
  // is shorter. y is shifted only when the box is periodic in y.
  for (const bool periodicY : {false, true}) {
    BoxDef box;
    box.lengthX = 7.0;
    box.width = 3.0;
    box.periodicY = periodicY;
    for (double dx = -16.0; dx <= 16.0; dx += 0.37)
      for (double dy : {-8.3, -2.9, -1.4, 0.0, 1.6, 4.7}) {
        const Vec3 d(dx, dy, 0.8);
        const Vec3 m = box.minimumImage(d);
        const double kx = (m.x() - d.x()) / box.lengthX, ky = (m.y() - d.y()) / box.width;
        CHECK(kx == Approx(std::round(kx)).margin(1e-12));
        CHECK(ky == Approx(std::round(ky)).margin(1e-12));
        if (!periodicY) CHECK(m.y() == d.y());
        CHECK(m.z() == d.z());
        const int ny = periodicY ? 4 : 0;
        for (int i = -4; i <= 4; ++i)
          for (int j = -ny; j <= ny; ++j)
            CHECK(m.norm() <= (d + Vec3(i * box.lengthX, j * box.width, 0.0)).norm() + 1e-12);
      }
  }
}

TEST_CASE("wrapping shifts by whole periods into the box and keeps y between walls") {
  BoxDef walled;
  walled.lengthX = 5.0;
  walled.width = 2.0;
  BoxDef periodic = walled;
  periodic.periodicY = true;
  for (double x : {-12.3, -5.0, -0.25, 0.0, 2.5, 5.0, 9.75, 31.0})
    for (double y : {-3.5, 0.5, 2.0, 7.25}) {
      const Vec3 p(x, y, 1.5);
      const Vec3 w = periodic.wrap(p), v = walled.wrap(p);
      CHECK(w.x() >= 0.0);
      CHECK(w.x() < periodic.lengthX);
      CHECK(w.y() >= 0.0);
      CHECK(w.y() < periodic.width);
      const double kx = (w.x() - x) / periodic.lengthX, ky = (w.y() - y) / periodic.width;
      CHECK(kx == Approx(std::round(kx)).margin(1e-12));
      CHECK(ky == Approx(std::round(ky)).margin(1e-12));
      CHECK(v.x() == w.x());
      CHECK(v.y() == y);  // walls, not a period
      CHECK(w.z() == 1.5);
    }
}

TEST_CASE("the walls: floor at z = 0 and side walls at y = 0 and y = W, normals into the box") {
  BoxDef box;
  box.width = 3.5;
  // A point of the box lies on the inner side of every wall: (x - wallPoint) . normal > 0.
  const Vec3 inside(1.0, 1.2, 0.7);
  for (const WallId w : {WallId::Floor, WallId::SideLow, WallId::SideHigh}) {
    CHECK(BoxDef::wallNormal(w).norm() == 1.0);
    CHECK((inside - box.wallPoint(w)).dot(BoxDef::wallNormal(w)) > 0.0);
    CHECK(isWall(static_cast<int>(w)));
  }
  CHECK((inside - box.wallPoint(WallId::Floor)).dot(BoxDef::wallNormal(WallId::Floor)) == 0.7);
  CHECK((inside - box.wallPoint(WallId::SideLow)).dot(BoxDef::wallNormal(WallId::SideLow)) == 1.2);
  CHECK((inside - box.wallPoint(WallId::SideHigh)).dot(BoxDef::wallNormal(WallId::SideHigh)) ==
        Approx(3.5 - 1.2).epsilon(1e-15));
  // A y-periodic box has the floor only.
  CHECK(box.wallCount() == 3);
  box.periodicY = true;
  CHECK(box.wallCount() == 1);
  CHECK_FALSE(isWall(0));
}

TEST_CASE("a box round-trips through JSON and refuses unusable fields by name") {
  BoxDef b;
  b.lengthX = 1.0 / 3.0;
  b.width = 7.1;
  b.periodicY = true;
  b.height = 12.5;
  const nlohmann::json j = b;
  const BoxDef c = j.get<BoxDef>();
  CHECK(c.lengthX == b.lengthX);
  CHECK(c.width == b.width);
  CHECK(c.periodicY == b.periodicY);
  CHECK(c.height == b.height);
  CHECK_NOTHROW(c.validate());
  BoxDef bad;
  bad.width = 0.0;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("width"));
  bad = BoxDef{};
  bad.lengthX = std::nan("");
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("length_x"));
  // The box is geometry only: the walls' friction is refused here, named with where it belongs.
  CHECK_THROWS_WITH(nlohmann::json::parse(R"({"wall_friction": 0.3})").get<BoxDef>(),
                    Catch::StartsWith("box.wall_friction: unknown key"));
}
