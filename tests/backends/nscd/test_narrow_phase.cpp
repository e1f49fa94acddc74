// The nscd narrow phase (backends/nscd/narrow_phase.hpp): collideAll on a team of threads gives
// the single-thread contacts, bit for bit and in the same order, and both (each pinacoid placed
// once a step) those of collidePair (the pair's bodies placed for it); an out-of-memory in a
// thread of the team comes out of collideAll as std::bad_alloc.
#include <catch2/catch.hpp>
#include <new>
#include <set>
#include <vector>

#include "backends/nscd/narrow_phase.hpp"
#include "tests/backends/nscd/nscd_problems.hpp"
#include "tests/support/failing_allocation.hpp"

using namespace confpack;
using core::Vec3;
using testing::candidatePairs;
using testing::pile;
using testing::sameBits;

namespace {

/// A deposited pinacoid pile (polyhedron pairs of all contact types, and wall contacts), its poses
/// as the phase takes them, and its candidate pairs at a large alert distance, so that many pairs,
/// of every kind, become contacts.
struct PinacoidPile {
  core::SystemDef s = pile(core::ShapeKind::Pinacoid, 10.0, 6.0, 800);
  std::vector<Vec3> positions;
  std::vector<core::Quat> orientations;
  nscd::NarrowPhase narrow{s.box, s.grains, 0.5};
  std::vector<nscd::CandidatePair> pairs = candidatePairs(s, narrow);
  PinacoidPile() {
    for (const core::Grain& g : s.grains) {
      positions.push_back(g.position);
      orientations.push_back(g.orientation);
    }
  }
};

}  // namespace

TEST_CASE("nscd narrow phase: collideAll on 2 threads returns the single-thread contacts in the same order",
          "[nscd][threads]") {
  PinacoidPile p;
  auto& [s, positions, orientations, narrow, pairs] = p;
  INFO("candidate pairs " << pairs.size());
  REQUIRE(pairs.size() >= 2 * nscd::NarrowPhase::kMinPairsPerThread);

  std::vector<nscd::ContactGeometry> one, two;
  narrow.collideAll(pairs, positions, orientations, one, 1);
  narrow.collideAll(pairs, positions, orientations, two, 2);
  narrow.collideAll(pairs, positions, orientations, two, 2);  // buffers reused
  // The reference: the plain loops over pairs, then over grains against the walls.
  std::vector<nscd::ContactGeometry> plain;
  for (const auto& pair : pairs) narrow.collidePair(pair, positions, orientations, plain);
  std::size_t walls = 0;
  for (std::size_t i = 0; i < s.grains.size(); ++i)
    narrow.collideWalls(static_cast<int>(i), positions, orientations, plain);
  for (const auto& c : plain) walls += core::isWall(c.b);
  REQUIRE(walls > 0);
  REQUIRE(plain.size() > walls + 500);
  std::set<int> pointCounts;
  for (const auto& c : plain) pointCounts.insert(c.pointCount);
  CHECK(pointCounts.size() >= 3);  // simple, double and triple contacts are all there
  std::size_t images = 0;          // pairs across the periodic side, placed for the pair
  for (const auto& c : plain) images += !core::isWall(c.b) && (c.shiftX != 0 || c.shiftY != 0);
  CHECK(images > 0);

  REQUIRE(one.size() == plain.size());
  REQUIRE(two.size() == plain.size());
  std::size_t bad = 0;
  for (std::size_t c = 0; c < plain.size(); ++c) {
    for (const auto* x : {&one[c], &two[c]}) {
      const nscd::ContactGeometry& y = plain[c];
      bool same = x->a == y.a && x->b == y.b && x->shiftX == y.shiftX && x->shiftY == y.shiftY && x->type == y.type &&
                  x->feature == y.feature && sameBits(x->normal, y.normal) && x->pointCount == y.pointCount;
      for (int p = 0; same && p < y.pointCount; ++p)
        same = sameBits(x->points[p], y.points[p]) && sameBits(x->gaps[p], y.gaps[p]);
      bad += !same;
    }
  }
  CHECK(bad == 0);
}

TEST_CASE("nscd narrow phase: an allocation failing in a thread of the team comes out of collideAll as std::bad_alloc",
          "[nscd][threads]") {
  // Before, the exception left the OpenMP region and the runtime aborted the program (SIGABRT)
  // instead of "out of memory while ...", exit 1.
  PinacoidPile p;
  auto& [s, positions, orientations, narrow, pairs] = p;
  REQUIRE(pairs.size() >= 2 * nscd::NarrowPhase::kMinPairsPerThread);
  std::vector<nscd::ContactGeometry> one, two;
  {
    // The first call of a phase runs the team (ThreadChoice's trial), whose second thread's
    // contact list is still empty: its first contact allocates.
    const testing::FailAllocationsOffThisThread outOfMemory;
    CHECK_THROWS_AS(narrow.collideAll(pairs, positions, orientations, two, 2), std::bad_alloc);
    CHECK(testing::FailAllocationsOffThisThread::refused() > 0);
  }
  // The phase is whole afterwards: the next calls give the single-thread contacts.
  narrow.collideAll(pairs, positions, orientations, one, 1);
  narrow.collideAll(pairs, positions, orientations, two, 2);
  REQUIRE(two.size() == one.size());
  std::size_t bad = 0;
  for (std::size_t c = 0; c < one.size(); ++c)
    bad += one[c].a != two[c].a || one[c].b != two[c].b || !sameBits(one[c].normal, two[c].normal);
  CHECK(bad == 0);
}
