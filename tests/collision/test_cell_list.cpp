// The periodic cell list (collision/cell_list.hpp) against brute force: the pair search gives
// exactly the pairs within the cutoff (minimum image) in the documented (i, j) order, and the
// region queries every periodic image within the radius, each exactly once.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

#include "collision/cell_list.hpp"
#include "core/random.hpp"
#include "tests/support/brute_force.hpp"

using namespace confpack::core;
using confpack::collision::CellList;
using confpack::collision::ImageHit;

namespace {

using confpack::testing::imagesNear;
using Hit = confpack::testing::ImageHit;

// ---------------------------------------------------------------------------------------------
// Region queries.

std::vector<Hit> fromList(const CellList& list, const Vec3& p, double r) {
  std::vector<Hit> out;
  list.forEachNear(p, r,
                   [&](const ImageHit& h) { out.emplace_back(h.id, h.position.x(), h.position.y(), h.position.z()); });
  std::sort(out.begin(), out.end());
  return out;
}

void compareImagesWithBruteForce(const BoxDef& box, double cell, double radius, int nPoints, bool byInsert) {
  Rng rng(11, StreamId::Test);
  CellList list(box, cell);
  std::vector<Vec3> pts;
  for (int i = 0; i < nPoints; ++i) {
    const Vec3 p(rng.uniform(0.0, box.lengthX), rng.uniform(0.0, box.width), rng.uniform(0.0, 6.0));
    pts.push_back(p);
    if (byInsert) list.insert(i, p);
  }
  if (!byInsert) list.build(pts);
  REQUIRE(list.size() == static_cast<std::size_t>(nPoints));
  std::size_t total = 0;
  for (int q = 0; q < 200; ++q) {
    // Query points also outside the box along the periodic directions.
    const Vec3 p(rng.uniform(-box.lengthX, 2.0 * box.lengthX),
                 box.periodicY ? rng.uniform(-box.width, 2.0 * box.width) : rng.uniform(0.0, box.width),
                 rng.uniform(-1.0, 7.0));
    const auto expected = imagesNear(box, pts, p, radius);
    // Image coordinates may differ in the last bit (stored wrapped + shift): compare ids and
    // coordinates to 1e-12.
    const auto got = fromList(list, p, radius);
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

// ---------------------------------------------------------------------------------------------
// Pair search.

struct Pair {
  int i = 0;
  int j = 0;
  Vec3 separation = Vec3::Zero();
};

std::vector<Pair> pairsOf(const CellList& list, double cutoff, int threads = 1) {
  std::vector<Pair> out;
  std::vector<std::vector<Pair>> team;
  auto emit = [cutoff](std::vector<Pair>& o, int i, int j, int, const Vec3& sep, const Vec3&) {
    if (sep.norm() < cutoff) o.push_back({i, j, sep});
  };
  list.findPairs<&Pair::j>(emit, out, threads, team);
  return out;
}

// n points in `box` with z in [0, zMax], some outside it by up to `outside` along x (and y), as a
// predicted configuration can be.
std::vector<Vec3> randomPoints(const BoxDef& box, int n, double zMax, double outside, std::uint64_t seed) {
  Rng rng(seed, StreamId::Test);
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i)
    p.emplace_back(rng.uniform(-outside, box.lengthX + outside), rng.uniform(-outside, box.width + outside),
                   rng.uniform(0.0, zMax));
  return p;
}

void comparePairsWithBruteForce(const BoxDef& box, const std::vector<Vec3>& p, double cutoff) {
  CellList list(box, cutoff);
  list.build(p);
  const std::vector<Pair> got = pairsOf(list, cutoff);
  const auto expected = confpack::testing::pairsWithinCutoff(box, p, cutoff);
  std::vector<std::pair<int, int>> keys;
  for (const Pair& q : got) keys.emplace_back(q.i, q.j);
  CHECK(keys == expected);  // the same pairs, in the same (i, j) order
  // The separation is BoxDef::minimumImage's, bit for bit.
  bool sameBits = true;
  for (const Pair& q : got) {
    const Vec3 ref = box.minimumImage(p[static_cast<std::size_t>(q.j)] - p[static_cast<std::size_t>(q.i)]);
    sameBits = sameBits && q.separation == ref;
  }
  CHECK(sameBits);
}

}  // namespace

TEST_CASE("cell list region queries find exactly the periodic images within the radius", "[collision][cells]") {
  BoxDef box;
  box.lengthX = 7.3;
  box.width = 5.1;
  const bool byInsert = GENERATE(true, false);
  SECTION("side walls along y") {
    box.periodicY = false;
    compareImagesWithBruteForce(box, 1.0, 1.7, 150, byInsert);
  }
  SECTION("periodic along y") {
    box.periodicY = true;
    compareImagesWithBruteForce(box, 1.0, 1.7, 150, byInsert);
  }
  SECTION("periods shorter than the query: several images of one point") {
    box.lengthX = 1.5;
    box.width = 1.2;
    box.periodicY = true;
    compareImagesWithBruteForce(box, 1.0, 2.1, 10, byInsert);
  }
}

TEST_CASE("cell list cells tile the period and are at least the cutoff", "[collision][cells]") {
  BoxDef box;
  box.lengthX = 20.0;
  box.width = 4.0;
  CellList list(box, 1.1);
  CHECK(list.cellsX() == 18);
  CHECK(list.cellsY() == 3);
  CHECK(list.cellSize().x() * list.cellsX() == Approx(20.0));
  CHECK(list.cellSize().x() >= 1.1);
  CHECK(list.cellSize().y() >= 1.1);
  CHECK_THROWS_AS(CellList(box, 0.0), std::invalid_argument);
  BoxDef flat = box;
  flat.width = -1.0;
  CHECK_THROWS_AS(CellList(flat, 1.0), std::invalid_argument);
  // Stored positions are wrapped into the box, with the image shift reported.
  list.insert(3, Vec3(-0.5, 1.0, 2.0));
  const auto hits = list.near(Vec3(19.5, 1.0, 2.0), 1e-9);
  REQUIRE(hits.size() == 1);
  CHECK(hits[0].id == 3);
  CHECK(hits[0].position.x() == Approx(19.5));
  CHECK(hits[0].shiftX == 0);
  const auto below = list.near(Vec3(-0.5, 1.0, 2.0), 1e-9);
  REQUIRE(below.size() == 1);
  CHECK(below[0].shiftX == -1);
}

TEST_CASE("cell list region queries report in layer, row, column, arrival order", "[collision][cells]") {
  BoxDef box;
  box.lengthX = 4.0;
  box.width = 4.0;
  CellList list(box, 1.0);
  // More points in one cell than its first room (re-laid out on the way), and others around.
  const std::vector<Vec3> points = {{1.5, 1.5, 0.5}, {1.2, 1.1, 0.2}, {2.5, 1.5, 0.5}, {1.9, 1.9, 0.9},
                                    {1.5, 2.5, 0.5}, {1.1, 1.8, 0.1}, {1.5, 1.5, 1.5}, {1.3, 1.3, 0.3},
                                    {1.6, 1.2, 0.6}, {0.5, 1.5, 0.5}};
  for (std::size_t k = 0; k < points.size(); ++k) list.insert(static_cast<int>(k), points[k]);
  std::vector<int> order;
  list.forEachInBox(Vec3(0.0, 0.0, 0.0), Vec3(3.9, 3.9, 3.9), [&](const ImageHit& h) { order.push_back(h.id); });
  // Layer 0: row 1 (columns 0, 1, 2), then row 2; layer 1. Within cell (1, 1, 0): arrival.
  CHECK(order == std::vector<int>{9, 0, 1, 3, 5, 7, 8, 2, 4, 6});
}

TEST_CASE("cell list pair search gives exactly the brute-force pairs within the cutoff, sorted by (i, j)",
          "[collision][cells]") {
  const bool periodicY = GENERATE(false, true);
  BoxDef box;
  box.periodicY = periodicY;
  SECTION("random points, some outside the box, several cutoffs") {
    box.lengthX = 9.0;
    box.width = 7.0;
    const auto p = randomPoints(box, 400, 6.0, 0.3, periodicY ? 2 : 1);
    for (const double cutoff : {0.7, 1.1, 2.9}) comparePairsWithBruteForce(box, p, cutoff);
    CHECK(confpack::testing::pairsWithinCutoff(box, p, 0.7).size() > 100);  // not vacuous
  }
  SECTION("two or three cells a period: each neighbouring cell once") {
    box.lengthX = 2.5;
    box.width = 3.3;
    const auto p = randomPoints(box, 120, 3.0, 0.0, 9);
    comparePairsWithBruteForce(box, p, 1.1);  // 2 cells along x, 3 along y
    comparePairsWithBruteForce(box, p, 1.2);  // 2 and 2
  }
  SECTION("a grain far above the pile, a box far larger than its grains: coarsened grids") {
    box.lengthX = 1e5;
    box.width = periodicY ? 1e5 : 50.0;
    Rng rng(7, StreamId::Test, 2);
    std::vector<Vec3> p;
    for (int k = 0; k < 60; ++k)
      p.emplace_back(std::fmod(box.lengthX + rng.uniform(-2.0, 2.0), box.lengthX), rng.uniform(0.5, 3.0),
                     rng.uniform(0.5, 5.0));
    p.emplace_back(0.5 * box.lengthX, 0.5 * box.width, 0.5);
    p.emplace_back(1.0, 1.0, 1e12);
    CellList list(box, 1.0);
    list.build(p);
    CHECK(static_cast<double>(list.cellsX()) * list.cellsY() * list.cellsZ() <=
          CellList::kMaxCellsPerPoint * static_cast<double>(p.size()) + CellList::kSpareCells);
    comparePairsWithBruteForce(box, p, 1.0);
    CHECK(confpack::testing::pairsWithinCutoff(box, p, 1.0).size() > 50);
  }
}

TEST_CASE("a box of 1e58 cutoffs: at most kMaxCellsPerAxis cells before and after build, the same pairs",
          "[collision][cells]") {
  // fuzz_packing (UBSan, clang): a packing whose length_x was 2.7e58 made the constructor cast
  // 2.7e58 cells to an int before build() could coarsen them.
  BoxDef box;
  box.lengthX = 2.6666666666666667e58;
  box.width = 2.0;
  box.periodicY = GENERATE(false, true);
  CellList list(box, 1.0);
  CHECK(list.cellsX() == static_cast<int>(CellList::kMaxCellsPerAxis));
  CHECK(list.cellsY() == 2);
  std::vector<Vec3> p;
  for (int k = 0; k < 30; ++k) p.emplace_back(0.4 * k, 1.0 + 0.3 * std::sin(k), 0.5 + 0.2 * (k % 3));
  list.build(p);
  CHECK(list.cellsX() >= 1);
  comparePairsWithBruteForce(box, p, 1.0);
  CHECK(confpack::testing::pairsWithinCutoff(box, p, 1.0).size() > 20);
}

TEST_CASE("cell list pair search on a team gives the one-thread list bit for bit", "[collision][cells][threads]") {
  BoxDef box;
  box.lengthX = 14.0;
  box.width = 8.0;
  box.periodicY = GENERATE(false, true);
  const auto p = randomPoints(box, 1500, 12.0, 0.1, 21);
  CellList list(box, 1.1);
  list.build(p);
  const std::vector<Pair> one = pairsOf(list, 1.1, 1);
  const std::vector<Pair> team = pairsOf(list, 1.1, 2);
  REQUIRE(one.size() == team.size());
  CHECK(std::memcmp(one.data(), team.data(), one.size() * sizeof(Pair)) == 0);
  CHECK(one.size() > 1000);
}

TEST_CASE("cell list toSlotOrder follows the slots findPairs reports", "[collision][cells]") {
  BoxDef box;
  box.lengthX = 6.0;
  box.width = 6.0;
  const auto p = randomPoints(box, 200, 4.0, 0.0, 4);
  std::vector<double> tag(p.size());
  for (std::size_t k = 0; k < p.size(); ++k) tag[k] = static_cast<double>(k);
  CellList list(box, 1.0);
  list.build(p);
  std::vector<double> bySlot;
  list.toSlotOrder(std::span<const double>(tag), bySlot);
  bool consistent = true;
  std::vector<Pair> out;
  list.findPairs<&Pair::j>(
      [&](std::vector<Pair>& o, int i, int j, int slot, const Vec3& sep, const Vec3&) {
        consistent = consistent && bySlot[static_cast<std::size_t>(slot)] == static_cast<double>(j);
        o.push_back({i, j, sep});
      },
      out);
  CHECK(consistent);
  CHECK(!out.empty());
}
