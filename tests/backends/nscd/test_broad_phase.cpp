// The nscd broad phase (backends/nscd/broad_phase.hpp): exactly the pairs of a brute-force
// search over the periodic images, on one thread or a team; an out-of-memory in a thread of the
// team comes out of it as std::bad_alloc.
#include <catch2/catch.hpp>
#include <cstdint>
#include <new>
#include <set>
#include <tuple>
#include <vector>

#include "backends/nscd/broad_phase.hpp"
#include "core/random.hpp"
#include "tests/support/brute_force.hpp"
#include "tests/support/failing_allocation.hpp"

using namespace confpack;
using core::Vec3;

namespace {

/// n grain centres in `box` up to height zMax, some slightly outside it in x as the predicted
/// configuration can be, with reaches in [0.3, 0.55].
struct Points {
  std::vector<Vec3> p;
  std::vector<double> reach;
};
Points randomPoints(const core::BoxDef& box, int n, double zMax, std::uint64_t seed) {
  core::Rng rng(seed, core::StreamId::Test);
  Points out;
  for (int i = 0; i < n; ++i) {
    out.p.emplace_back(rng.uniform(-0.1, box.lengthX + 0.1), rng.uniform(0.0, box.width), rng.uniform(0.0, zMax));
    out.reach.push_back(rng.uniform(0.3, 0.55));
  }
  return out;
}

}  // namespace

TEST_CASE("nscd broad phase finds exactly the pairs of a brute-force minimum-image search", "[nscd]") {
  const bool periodicY = GENERATE(false, true);
  core::BoxDef bx;
  bx.lengthX = 7.0;
  bx.width = 6.0;
  bx.periodicY = periodicY;
  const auto [p, reach] = randomPoints(bx, 300, 6.0, 5);
  nscd::BroadPhase bp(bx, 0.55);
  std::vector<nscd::CandidatePair> pairs;
  bp.findPairs(p, reach, pairs);
  std::set<testing::ImagePairKey> found;
  for (const auto& c : pairs) found.insert({c.a, c.b, c.shiftX, c.shiftY});
  const auto expected = testing::pairsWithin(bx, p, reach);
  CHECK(found.size() == pairs.size());  // no duplicates
  CHECK(found == expected);
  CHECK(expected.size() > 100);  // the test is not vacuous
}

TEST_CASE("nscd broad phase: 2 threads give the single-thread pair list, which is the brute-force one",
          "[nscd][threads]") {
  const bool periodicY = GENERATE(false, true);
  core::BoxDef bx;
  bx.lengthX = 14.0;
  bx.width = 8.0;
  bx.periodicY = periodicY;
  const int n = 1500;
  REQUIRE(n >= 2 * nscd::BroadPhase::kMinGrainsPerThread);
  const auto [p, reach] = randomPoints(bx, n, 12.0, 21);
  std::vector<nscd::CandidatePair> sequential, parallel;
  nscd::BroadPhase(bx, 0.55, 1).findPairs(p, reach, sequential);
  nscd::BroadPhase bp2(bx, 0.55, 2);
  bp2.findPairs(p, reach, parallel);
  bp2.findPairs(p, reach, parallel);  // buffers reused from the first call
  REQUIRE(sequential.size() == parallel.size());
  bool same = true;
  for (std::size_t k = 0; k < sequential.size(); ++k)
    same = same && sequential[k].a == parallel[k].a && sequential[k].b == parallel[k].b &&
           sequential[k].shiftX == parallel[k].shiftX && sequential[k].shiftY == parallel[k].shiftY;
  CHECK(same);
  // Sorted by (a, b), and the set is exactly the brute-force minimum-image one.
  for (std::size_t k = 1; k < parallel.size(); ++k)
    CHECK(std::tie(parallel[k - 1].a, parallel[k - 1].b) < std::tie(parallel[k].a, parallel[k].b));
  std::set<testing::ImagePairKey> found;
  for (const auto& c : parallel) found.insert({c.a, c.b, c.shiftX, c.shiftY});
  CHECK(found == testing::pairsWithin(bx, p, reach));
}

TEST_CASE("nscd broad phase: an allocation failing in a thread of the team comes out of findPairs as std::bad_alloc",
          "[nscd][threads]") {
  // Before, the exception left the OpenMP region and the runtime aborted the program (SIGABRT).
  core::BoxDef bx;
  bx.lengthX = 14.0;
  bx.width = 8.0;
  const auto [p, reach] = randomPoints(bx, 1500, 12.0, 21);
  nscd::BroadPhase bp2(bx, 0.55, 2);
  std::vector<nscd::CandidatePair> sequential, parallel;
  {
    // The first call runs the team (ThreadChoice's trial); the second thread's pair list is empty.
    const testing::FailAllocationsOffThisThread outOfMemory;
    CHECK_THROWS_AS(bp2.findPairs(p, reach, parallel), std::bad_alloc);
    CHECK(testing::FailAllocationsOffThisThread::refused() > 0);
  }
  // Whole afterwards: the single-thread pair list.
  nscd::BroadPhase(bx, 0.55, 1).findPairs(p, reach, sequential);
  bp2.findPairs(p, reach, parallel);
  REQUIRE(parallel.size() == sequential.size());
  bool same = true;
  for (std::size_t k = 0; k < sequential.size(); ++k)
    same = same && sequential[k].a == parallel[k].a && sequential[k].b == parallel[k].b;
  CHECK(same);
}
