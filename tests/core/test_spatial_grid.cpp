// SpatialGrid against brute force: every periodic image within the radius, each exactly once.
#include <algorithm>
#include <catch2/catch.hpp>
#include <tuple>
#include <vector>

#include "core/random.hpp"
#include "core/spatial_grid.hpp"
#include "tests/support/brute_force.hpp"

using namespace confpack::core;

namespace {

using confpack::testing::imagesNear;
using Hit = confpack::testing::ImageHit;

std::vector<Hit> fromGrid(const SpatialGrid& grid, const Vec3& p, double r) {
  std::vector<Hit> out;
  grid.forEachNear(p, r, [&](int id, const Vec3& im) { out.emplace_back(id, im.x(), im.y(), im.z()); });
  std::sort(out.begin(), out.end());
  return out;
}

void compareWithBruteForce(const BoxDef& box, double cell, double radius, int nPoints) {
  Rng rng(11, StreamId::Test);
  SpatialGrid grid(box, cell);
  std::vector<Vec3> pts;
  for (int i = 0; i < nPoints; ++i) {
    const Vec3 p(rng.uniform(0.0, box.lengthX), rng.uniform(0.0, box.width), rng.uniform(0.0, 6.0));
    pts.push_back(p);
    grid.insert(i, p);
  }
  REQUIRE(grid.size() == static_cast<std::size_t>(nPoints));
  std::size_t total = 0;
  for (int q = 0; q < 200; ++q) {
    // Query points also outside the box along the periodic directions.
    const Vec3 p(rng.uniform(-box.lengthX, 2.0 * box.lengthX),
                 box.periodicY ? rng.uniform(-box.width, 2.0 * box.width) : rng.uniform(0.0, box.width),
                 rng.uniform(-1.0, 7.0));
    const auto expected = imagesNear(box, pts, p, radius);
    // Image coordinates may differ in the last bit (stored wrapped + shift): compare ids and
    // coordinates to 1e-12.
    const auto got = fromGrid(grid, p, radius);
    REQUIRE(got.size() == expected.size());
    for (std::size_t k = 0; k < got.size(); ++k) {
      REQUIRE(std::get<0>(got[k]) == std::get<0>(expected[k]));
      REQUIRE(std::get<1>(got[k]) == Approx(std::get<1>(expected[k])).margin(1e-12));
      REQUIRE(std::get<2>(got[k]) == Approx(std::get<2>(expected[k])).margin(1e-12));
    }
    total += got.size();
  }
  CHECK(total > 0);  // the comparison is not vacuous
}

}  // namespace

TEST_CASE("spatial grid finds exactly the periodic images within the radius", "[core][grid]") {
  BoxDef box;
  box.lengthX = 7.3;
  box.width = 5.1;
  SECTION("side walls along y") {
    box.periodicY = false;
    compareWithBruteForce(box, 1.0, 1.7, 150);
  }
  SECTION("periodic along y") {
    box.periodicY = true;
    compareWithBruteForce(box, 1.0, 1.7, 150);
  }
  SECTION("periods shorter than the query: several images of one point") {
    box.lengthX = 1.5;
    box.width = 1.2;
    box.periodicY = true;
    compareWithBruteForce(box, 1.0, 2.1, 10);
  }
}

TEST_CASE("spatial grid cells tile the period and are at least the requested size", "[core][grid]") {
  BoxDef box;
  box.lengthX = 20.0;
  box.width = 4.0;
  SpatialGrid grid(box, 1.1);
  CHECK(grid.cellsX() == 18);
  CHECK(grid.cellsY() == 3);
  CHECK(grid.cellSize().x() * grid.cellsX() == Approx(20.0));
  CHECK(grid.cellSize().x() >= 1.1);
  CHECK(grid.cellSize().y() >= 1.1);
  CHECK_THROWS_AS(SpatialGrid(box, 0.0), std::invalid_argument);
  // Stored positions are wrapped into the box.
  grid.insert(3, Vec3(-0.5, 1.0, 2.0));
  const auto hits = grid.near(Vec3(19.5, 1.0, 2.0), 1e-9);
  REQUIRE(hits.size() == 1);
  CHECK(hits[0].id == 3);
  CHECK(hits[0].position.x() == Approx(19.5));
}
