// neighbourPairs (analysis/neighbour_pairs.hpp): exactly the pairs of a brute-force search over
// every periodic image, each once, sorted by (i, j), with the minimum-image separation.
#include <catch2/catch.hpp>
#include <cmath>
#include <set>
#include <tuple>
#include <vector>

#include "analysis/neighbour_pairs.hpp"
#include "core/random.hpp"
#include "tests/support/brute_force.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;

TEST_CASE("neighbour pairs are exactly the brute-force pairs over the periodic images") {
  for (const bool periodicY : {false, true})
    for (const double extra : {0.0, 0.3}) {
      core::Packing p;
      p.box.lengthX = 9.0;
      p.box.width = 7.0;
      p.box.periodicY = periodicY;
      core::Rng rng(13, core::StreamId::Test, periodicY ? 1 : 0);
      for (int k = 0; k < 300; ++k) {
        const core::Vec3 x(rng.uniform(0.0, p.box.lengthX), rng.uniform(0.0, p.box.width), rng.uniform(0.0, 5.0));
        const double size = rng.uniform(0.5, 1.0);
        p.grains.push_back(k % 3 == 0 ? testing::pinacoid(size, x, rng.uniformQuaternion()) : testing::sphere(size, x));
      }
      std::vector<core::Vec3> positions;
      std::vector<double> radii;
      for (const auto& g : p.grains) {
        positions.push_back(g.position);
        radii.push_back(g.boundingRadius());
      }
      const auto expected = testing::pairsWithin(p.box, positions, radii, extra);
      std::set<testing::ImagePairKey> found;
      std::size_t count = 0;
      const auto pairs = analysis::neighbourPairs(p, extra);
      for (std::size_t k = 1; k < pairs.size(); ++k)
        CHECK(std::tie(pairs[k - 1].i, pairs[k - 1].j) < std::tie(pairs[k].i, pairs[k].j));
      for (const auto& q : pairs) {
        ++count;
        CHECK(q.i < q.j);
        // separation = x_j + (sx L_x, sy W, 0) - x_i with whole shifts.
        const core::Vec3 shift = q.separation - (positions[q.j] - positions[q.i]);
        const int sx = static_cast<int>(std::lround(shift.x() / p.box.lengthX));
        const int sy = static_cast<int>(std::lround(shift.y() / p.box.width));
        CHECK(shift.x() == Approx(sx * p.box.lengthX).margin(1e-12));
        CHECK(shift.y() == Approx(sy * p.box.width).margin(1e-12));
        CHECK(shift.z() == 0.0);
        found.insert({q.i, q.j, sx, sy});
      }
      CHECK(found.size() == count);  // each pair once
      CHECK(found == expected);
      CHECK(expected.size() > 100);  // not vacuous
    }
}

TEST_CASE("a box or a pile far larger than its grains gets a grid sized by the grains, with the same pairs") {
  // Issue 23: a 1e5 x 1e5 biperiodic box of a few grains allocated 2e9 cells (8 GB), and
  // fuzz_packing found a box 1.8e16 wide whose cell count overflowed an int (UBSan).
  struct Case {
    double lengthX, width, zSpread;
    bool periodicY;
  };
  for (const Case& c :
       {Case{1e5, 1e5, 5.0, true}, Case{3.0, 18110810196449834.0, 5.0, false}, Case{1e9, 50.0, 1e12, false}}) {
    core::Packing p;
    p.box.lengthX = c.lengthX;
    p.box.width = c.width;
    p.box.periodicY = c.periodicY;
    core::Rng rng(7, core::StreamId::Test, 2);
    // A cluster near the origin, with pairs across the periodic boundary of x, and lone grains
    // far away along every axis.
    for (int k = 0; k < 40; ++k)
      p.grains.push_back(testing::sphere(1.0, core::Vec3(std::fmod(c.lengthX + rng.uniform(-2.0, 2.0), c.lengthX),
                                                         rng.uniform(0.5, 3.0), rng.uniform(0.5, 5.0))));
    p.grains.push_back(testing::sphere(1.0, core::Vec3(0.5 * c.lengthX, 0.5 * c.width, 0.5)));
    p.grains.push_back(testing::sphere(1.0, core::Vec3(1.0, 1.0, c.zSpread)));
    std::vector<core::Vec3> positions;
    std::vector<double> radii;
    for (const auto& g : p.grains) {
      positions.push_back(g.position);
      radii.push_back(g.boundingRadius());
    }
    const auto expected = testing::pairsWithin(p.box, positions, radii, 0.0);
    std::set<testing::ImagePairKey> found;
    for (const auto& q : analysis::neighbourPairs(p)) {
      const core::Vec3 shift = q.separation - (positions[q.j] - positions[q.i]);
      found.insert({q.i, q.j, static_cast<int>(std::lround(shift.x() / p.box.lengthX)),
                    static_cast<int>(std::lround(shift.y() / p.box.width))});
    }
    CHECK(found == expected);
    CHECK(expected.size() > 50);  // not vacuous
  }
}
