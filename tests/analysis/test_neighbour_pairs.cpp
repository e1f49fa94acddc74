// neighbourPairs (analysis/neighbour_pairs.hpp): the cell list finds exactly the pairs of a
// brute-force search over every periodic image, each once, with the minimum-image separation.
#include <catch2/catch.hpp>
#include <cmath>
#include <set>
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
      for (const auto& q : analysis::neighbourPairs(p, extra)) {
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
