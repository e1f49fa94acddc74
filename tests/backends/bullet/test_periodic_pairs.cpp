// PeriodicPairFinder (backends/bullet/periodic_pairs.hpp): exactly the pairs that touch across a
// periodic face, in long boxes and in short ones (where a grain can touch two images of another),
// as an all-pairs search over every image finds them.
#include <catch2/catch.hpp>
#include <set>
#include <vector>

#include "backends/bullet/periodic_pairs.hpp"
#include "core/random.hpp"
#include "tests/support/brute_force.hpp"

using namespace confpack;
using core::Vec3;

TEST_CASE("bullet periodic pair finder agrees with all-pairs in long and short boxes", "[bullet]") {
  for (const bool periodicY : {false, true}) {
    for (const double length : {2.5, 9.0}) {  // 2.5: less than 3 reaches, several images in reach
      core::BoxDef box;
      box.lengthX = length;
      box.width = length;
      box.periodicY = periodicY;
      core::Rng rng(3, core::StreamId::Test, periodicY ? 1 : 0);
      std::vector<Vec3> p;
      std::vector<double> r;
      for (int i = 0; i < 150; ++i) {
        p.emplace_back(rng.uniform() * length, rng.uniform() * length, rng.uniform() * 3.0);
        r.push_back(0.4 + 0.1 * rng.uniform());
      }
      const double thr = 0.02;
      const bullet::PeriodicPairFinder finder(box, 2.0 * 0.5 + thr);
      const auto found = finder.find(p, r, thr);
      // All-pairs reference over every image but the unshifted one.
      std::set<testing::ImagePairKey> keys;
      for (const auto& q : found) keys.insert({q.a, q.b, q.shiftX, q.shiftY});
      CHECK(keys.size() == found.size());
      CHECK(keys == testing::pairsWithin(box, p, r, thr, false));
      for (const auto& q : found) {
        CHECK(q.a < q.b);
        CHECK((q.shiftX != 0 || q.shiftY != 0));
        CHECK((p[q.b] + q.shift - p[q.a]).norm() < r[q.a] + r[q.b] + thr);
      }
    }
  }
}
