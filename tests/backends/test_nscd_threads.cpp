// The nscd backend's OpenMP phases (broad phase, narrow phase, per-body integration) must not
// change a single bit: a run with threads = 2 is the run with threads = 1. Every system here is
// large enough for the parallel paths to engage (see the kMin...PerThread thresholds).
#include <catch2/catch.hpp>
#include <cstring>
#include <set>
#include <tuple>

#include "backends/nscd/broad_phase.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_backend.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "backends/nscd/thread_choice.hpp"
#include "core/deposition.hpp"
#include "core/random.hpp"

using namespace confpack;
using core::Vec3;

namespace {

bool sameBits(double x, double y) {
  return std::memcmp(&x, &y, sizeof x) == 0;
}

template <class V>
bool sameBits(const V& x, const V& y) {
  for (int k = 0; k < x.size(); ++k)
    if (!sameBits(x[k], y[k])) return false;
  return true;
}

bool sameBits(const core::Quat& x, const core::Quat& y) {
  return sameBits(x.coeffs(), y.coeffs());
}

/// A deposited pile (docs/model.md, "Deposition") of n grains between side walls with friction 0.3,
/// every grain scaled by `grow` (placeholders circumscribe the largest grain, so a plain deposit
/// touches nowhere; grown grains touch and load each other from the first step).
core::SystemDef pile(core::ShapeKind shape, double lengthX, double width, std::size_t n, double grow = 1.0) {
  core::SystemDef s;
  s.box.lengthX = lengthX;
  s.box.width = width;
  s.box.periodicY = false;
  s.box.wallFriction = 0.3;
  core::PopulationDef population;
  population.shape = shape;
  core::DepositionDef def;
  def.grainCount = n;
  s.grains = core::deposit(s.box, population, def, 11).grains;
  for (core::Grain& g : s.grains) g.size *= grow;
  return s;
}

/// The broad phase's candidate pairs of the grains of `s` at their initial positions.
std::vector<nscd::CandidatePair> candidatePairs(const core::SystemDef& s, const nscd::NarrowPhase& narrow) {
  std::vector<Vec3> positions;
  std::vector<double> reach;
  for (std::size_t i = 0; i < s.grains.size(); ++i) {
    positions.push_back(s.grains[i].position);
    reach.push_back(narrow.reach(static_cast<int>(i)));
  }
  std::vector<nscd::CandidatePair> pairs;
  nscd::BroadPhase(s.box, narrow.maxReach()).findPairs(positions, reach, pairs);
  return pairs;
}

/// Steps the same system with threads = 1 and threads = 2 and requires identical bits in every
/// pose, velocity, contact and force at the end. With `teamRows`, the last step must have had
/// enough contact rows for MPRGP's passes (among them the warm start's impulses) to run on the team.
void requireSameRun(const core::SystemDef& s, int steps, double dt, bool teamRows) {
  // A capped solver keeps the test fast; convergence is not the point, identical iterates are.
  auto one = nscd::makeNscdBackend(s, {{"threads", 1}, {"max_iterations", 10}});
  auto two = nscd::makeNscdBackend(s, {{"threads", 2}, {"max_iterations", 10}});
  for (int k = 0; k < steps; ++k) {
    one->step(dt);
    two->step(dt);
  }
  // Not vacuous: the pile is loaded, its contacts carry force.
  INFO("contacts " << one->contacts().size() << ", grains " << s.grains.size() << ", rows "
                   << one->profile().contactPoints);
  REQUIRE(one->contacts().size() > s.grains.size() / 8);
  if (teamRows) REQUIRE(one->profile().contactPoints >= 4096);  // MPRGP's kParallelMin
  double total = 0.0;
  for (const auto& c : one->contacts()) total += c.normalForce();
  REQUIRE(total > 0.0);

  std::size_t badStates = 0;
  for (std::size_t i = 0; i < s.grains.size(); ++i) {
    const core::BodyState &x = one->states()[i], &y = two->states()[i];
    badStates += !(sameBits(x.position, y.position) && sameBits(x.orientation, y.orientation) &&
                   sameBits(x.velocity, y.velocity) && sameBits(x.angularVelocity, y.angularVelocity));
  }
  CHECK(badStates == 0);
  REQUIRE(one->contacts().size() == two->contacts().size());
  std::size_t badContacts = 0;
  for (std::size_t c = 0; c < one->contacts().size(); ++c) {
    const core::Contact &x = one->contacts()[c], &y = two->contacts()[c];
    bool same = x.a == y.a && x.b == y.b && x.type == y.type && sameBits(x.normal, y.normal) &&
                x.points.size() == y.points.size();
    for (std::size_t p = 0; same && p < x.points.size(); ++p)
      same = sameBits(x.points[p].position, y.points[p].position) &&
             sameBits(x.points[p].normalForce, y.points[p].normalForce) &&
             sameBits(x.points[p].tangentForce, y.points[p].tangentForce) && sameBits(x.points[p].gap, y.points[p].gap);
    badContacts += !same;
  }
  CHECK(badContacts == 0);
  // Same solver work too (the row order the solver sees is the same).
  CHECK(one->profile().iterations == two->profile().iterations);
  CHECK(sameBits(one->profile().residual, two->profile().residual));
}

}  // namespace

TEST_CASE("nscd broad phase: 2 threads give the single-thread pair list, which is the brute-force one",
          "[nscd][threads]") {
  const bool periodicY = GENERATE(false, true);
  core::BoxDef bx;
  bx.lengthX = 14.0;
  bx.width = 8.0;
  bx.periodicY = periodicY;
  core::Rng rng(21, core::StreamId::Test);
  const int n = 1500;
  REQUIRE(n >= 2 * nscd::BroadPhase::kMinGrainsPerThread);
  std::vector<Vec3> p;
  std::vector<double> reach;
  for (int i = 0; i < n; ++i) {
    // Some positions slightly outside the box, as the predicted configuration can be.
    p.emplace_back(rng.uniform(-0.1, bx.lengthX + 0.1), rng.uniform(0.0, bx.width), rng.uniform(0.0, 12.0));
    reach.push_back(rng.uniform(0.3, 0.55));
  }
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
  std::set<std::tuple<int, int, int, int>> found, expected;
  for (const auto& c : parallel) found.insert({c.a, c.b, c.shiftX, c.shiftY});
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const Vec3 raw = p[j] - p[i];
      const Vec3 d = bx.minimumImage(raw);
      if (d.norm() >= reach[i] + reach[j]) continue;
      expected.insert({i, j, static_cast<int>(std::lround((d.x() - raw.x()) / bx.lengthX)),
                       static_cast<int>(std::lround((d.y() - raw.y()) / bx.width))});
    }
  CHECK(found == expected);
}

TEST_CASE("nscd narrow phase: collideAll on 2 threads returns the single-thread contacts in the same order",
          "[nscd][threads]") {
  // A deposited pinacoid pile: polyhedron pairs (all contact types) and wall contacts.
  const core::SystemDef s = pile(core::ShapeKind::Pinacoid, 10.0, 6.0, 800);
  std::vector<Vec3> positions;
  std::vector<core::Quat> orientations;
  for (const core::Grain& g : s.grains) {
    positions.push_back(g.position);
    orientations.push_back(g.orientation);
  }
  // A large alert distance so that many pairs, of every kind, become contacts.
  nscd::NarrowPhase narrow(s.box, s.grains, 0.5);
  const std::vector<nscd::CandidatePair> pairs = candidatePairs(s, narrow);
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

TEST_CASE("nscd: a sphere pile stepped on 2 threads is bitwise the single-thread run", "[nscd][threads]") {
  // 2500 spheres: the broad phase runs on 2 threads (sphere-only systems collide on one).
  // Grown to the placeholder size (1.1 d): a touching, loaded pile from the start.
  requireSameRun(pile(core::ShapeKind::Sphere, 12.0, 8.0, 2500, 1.1), 4, 2e-3, true);
}

TEST_CASE("nscd: a pinacoid pile stepped on 2 threads is bitwise the single-thread run", "[nscd][threads]") {
  const core::SystemDef s = pile(core::ShapeKind::Pinacoid, 12.0, 6.0, 1200, 1.3);
  // The narrow phase runs on 2 threads: more than 2 x kMinPairsPerThread candidate pairs.
  const nscd::NarrowPhase narrow(s.box, s.grains, nscd::NscdSettings{}.alertDistance);
  const std::vector<nscd::CandidatePair> pairs = candidatePairs(s, narrow);
  INFO("candidate pairs " << pairs.size());
  REQUIRE(pairs.size() >= 2 * nscd::NarrowPhase::kMinPairsPerThread);
  requireSameRun(s, 30, 2e-3, false);
}

TEST_CASE("nscd: a pressed pinacoid pile between rough walls, warm started on 2 threads, is bitwise the "
          "single-thread run",
          "[nscd][threads]") {
  // Grown by half, the grains overlap their neighbours from the first step: thousands of rows
  // (angular, multi-point, wall friction), so that the solver's passes run on the team, and the
  // later steps are warm started from the cache.
  requireSameRun(pile(core::ShapeKind::Pinacoid, 28.0, 5.0, 3000, 1.5), 3, 2e-3, true);
}

TEST_CASE("nscd ThreadChoice keeps the faster of the team and one thread, and measures again every epoch",
          "[nscd][threads]") {
  using nscd::ThreadChoice;
  CHECK(ThreadChoice(1).next() == 1);
  for (const bool teamFaster : {true, false}) {
    ThreadChoice choice(2);
    const double teamTime = teamFaster ? 1e-3 : 8e-3, oneTime = 2e-3;
    int expectedLength = ThreadChoice::kEpoch;
    for (int epoch = 0; epoch < 3; ++epoch) {
      int teamCalls = 0, oneCalls = 0;
      int length = 0;
      int lengthSeen = 0;
      do {
        const int team = choice.next();
        REQUIRE((team == 1 || team == 2));
        if (length < ThreadChoice::kTrial) CHECK(team == 2);  // each epoch starts by timing both
        if (length >= ThreadChoice::kTrial && length < 2 * ThreadChoice::kTrial) CHECK(team == 1);
        (team == 2 ? teamCalls : oneCalls)++;
        choice.record(team == 2 ? teamTime : oneTime);
        if (++length == 2 * ThreadChoice::kTrial) lengthSeen = choice.epochLength();
      } while (length < 2 * ThreadChoice::kTrial || length < lengthSeen);
      // A losing team waits twice as long for its next trial; after the trials every call of the
      // epoch goes to the faster one.
      if (!teamFaster) expectedLength = std::min(2 * expectedLength, ThreadChoice::kMaxEpoch);
      CHECK(length == expectedLength);
      CHECK((teamFaster ? teamCalls : oneCalls) == length - ThreadChoice::kTrial);
    }
  }
}
