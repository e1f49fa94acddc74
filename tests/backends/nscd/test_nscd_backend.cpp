// The native contact dynamics backend (backends/nscd/nscd_backend.hpp) as a whole: time stepping,
// damping, resting contacts, warm start, pinacoid contact types, determinism and thread-count
// independence (the conformance suite covers what both backends share; the phases have their own
// files).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_backend.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "core/random.hpp"
#include "tests/backends/nscd/nscd_problems.hpp"
#include "tests/support/hash.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using core::Vec3;

namespace {

using confpack::testing::boxSystem;
using confpack::testing::candidatePairs;
using confpack::testing::pile;
using confpack::testing::pinacoid;
using confpack::testing::sameBits;
using confpack::testing::sphere;
using confpack::testing::topOf;
using confpack::testing::touchingSpheres;
using confpack::testing::withBottomAt;

/// Steps the same system with threads = 1 and threads = 2 and requires identical bits in every
/// pose, velocity, contact and force at the end. With `teamRows`, the last step must have had
/// enough contact rows for MPRGP's passes (among them the warm start's impulses) to run on the team.
void requireSameRun(const core::SystemDef& s, int steps, double dt, bool teamRows) {
  // A capped solver keeps the test fast; convergence is not the point, identical iterates are.
  core::SystemDef onTwo = s;
  onTwo.threads = 2;
  auto one = nscd::makeNscdBackend(s, {{"max_iterations", 10}});
  auto two = nscd::makeNscdBackend(onTwo, {{"max_iterations", 10}});
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

TEST_CASE("nscd free fall error is (theta - 1/2) g t dt", "[nscd]") {
  // q_{i+1} = q_i + dt ((1 - theta) v_i + theta v_{i+1}) with v_k = -g k dt sums to
  // z_n = z0 - g dt^2 (n (n - 1)/2 + theta n) = z0 - g t^2/2 - (theta - 1/2) g t dt.
  const double theta = GENERATE(0.5, 0.75, 1.0);
  const double dt = GENERATE(2e-3, 1e-2);
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 100.0)));
  auto b = nscd::makeNscdBackend(s, {{"theta", theta}});
  const int n = static_cast<int>(std::lround(2.0 / dt));
  for (int k = 0; k < n; ++k) b->step(dt);
  const double t = n * dt;
  const double expected = 100.0 - 0.5 * t * t - (theta - 0.5) * t * dt;
  CHECK(b->states()[0].position.z() == Approx(expected).epsilon(1e-13));
}

TEST_CASE("nscd damping: a loaded grain tends to F / (m c), and free flight and rest are untouched", "[nscd]") {
  const double c = 0.8, dt = 1e-3;
  const int n = 2000;
  SECTION("sliding on the frictionless floor under a body force F_x") {
    // Gravity (F_x, 0, -1): the floor carries the weight (so the grain is loaded) and nothing
    // balances F_x. Step 1 is undamped (nothing was loaded before it); then v <- q v + F_x dt with
    // q = exp(-c dt), so v_n = F_x dt (1 - q^n) / (1 - q), which tends to F_x / c.
    const double fx = 0.3;
    core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
    s.gravity = Vec3(fx, 0.0, -1.0);
    s.grains.push_back(sphere(1.0, Vec3(5.0, 5.0, 0.5)));
    auto b = nscd::makeNscdBackend(s, {{"damping", c}, {"damping_speed", nullptr}});  // no speed limit
    for (int k = 0; k < n; ++k) b->step(dt);
    const double q = std::exp(-c * dt);
    CHECK(b->states()[0].velocity.x() == Approx(fx * dt * (1.0 - std::pow(q, n)) / (1.0 - q)).epsilon(1e-12));
    CHECK(b->states()[0].velocity.x() < 0.85 * fx / c);  // far from undamped (fx n dt = 2 fx / c)
    CHECK(std::abs(b->states()[0].velocity.z()) < 1e-12);
    // Undamped, or faster than damping_speed from step 1 on (v_1 = F_x dt), the same grain keeps
    // the full acceleration.
    for (const nlohmann::json& options :
         {nlohmann::json::object(), nlohmann::json{{"damping", c}, {"damping_speed", 0.1 * fx * dt}}}) {
      auto free = nscd::makeNscdBackend(s, options);
      for (int k = 0; k < n; ++k) free->step(dt);
      CHECK(free->states()[0].velocity.x() == Approx(fx * n * dt).epsilon(1e-12));
    }
  }
  SECTION("free fall is exact: a grain without contact is not damped") {
    core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
    s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 100.0)));
    auto b = nscd::makeNscdBackend(s, {{"damping", c}});
    for (int k = 0; k < n; ++k) b->step(dt);
    const double t = n * dt;
    CHECK(b->states()[0].position.z() == Approx(100.0 - 0.5 * t * t).epsilon(1e-13));
  }
  SECTION("a resting column still carries k m g at its k-th contact") {
    core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
    for (int k = 0; k < 10; ++k) s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 0.5 + k)));
    auto b = nscd::makeNscdBackend(s, {{"damping", c}, {"tolerance", 1e-12}});
    for (int k = 0; k < n; ++k) b->step(dt);
    const double m = std::numbers::pi / 6.0;
    for (const core::Contact& c : b->contacts()) {
      const int below = c.b < 0 ? 0 : std::min(c.a, c.b) + 1;  // grains under this contact
      CHECK(c.normalForce() == Approx((10 - below) * m).epsilon(1e-9));
    }
    CHECK(b->contacts().size() == 10);
  }
}

TEST_CASE("nscd: a sphere falling on the floor stops dead at contact (no bounce, no overlap)", "[nscd]") {
  const double dt = GENERATE(1e-3, 5e-3);
  {
    core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
    s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 1.5037)));
    // Plain Gauss-Seidel solves an isolated contact exactly in one sweep (over-relaxation would
    // only get within the tolerance), so the oracle can be exact.
    auto b = nscd::makeNscdBackend(s, {{"relaxation", 1.0}});
    double minGap = 0.0, maxUp = 0.0;
    bool touched = false;
    for (int k = 0; k < static_cast<int>(2.0 / dt); ++k) {
      b->step(dt);
      const core::BodyState& st = b->states()[0];
      minGap = std::min(minGap, st.position.z() - 0.5);
      if (!b->contacts().empty() && b->contacts()[0].normalForce() > 0.0) touched = true;
      if (touched) maxUp = std::max(maxUp, st.velocity.z());
    }
    CHECK(touched);
    CHECK(minGap > -1e-12);  // never below the floor
    CHECK(maxUp < 1e-12);    // never moves up: e_n = 0
    CHECK(b->states()[0].velocity.norm() < 1e-12);
    CHECK(b->states()[0].position.z() == Approx(0.5).margin(1e-12));
  }
}

TEST_CASE("nscd: a small sphere dropped on a large one comes to rest on it and loads it", "[nscd]") {
  // e_n = 0: after the impact the small sphere sits on the large one; at rest the pair carries
  // the small weight and the floor both weights.
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  s.grains.push_back(sphere(0.5, Vec3(10.0, 5.0, 2.5)));
  s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 0.5)));
  auto b = nscd::makeNscdBackend(s, {{"tolerance", 1e-12}});
  const double dt = 2e-3;
  for (int k = 0; k < 1500; ++k) b->step(dt);
  const double m0 = std::numbers::pi / 6.0 * 0.125, m1 = std::numbers::pi / 6.0;
  CHECK(b->states()[0].velocity.norm() < 1e-12);
  CHECK(b->states()[0].position.z() == Approx(1.0 + 0.25).margin(1e-10));
  double floorForce = 0.0, pairForce = 0.0;
  for (const auto& c : b->contacts()) (c.b < 0 ? floorForce : pairForce) += c.normalForce();
  CHECK(pairForce == Approx(m0).epsilon(1e-9));
  CHECK(floorForce == Approx(m0 + m1).epsilon(1e-9));
}

TEST_CASE("nscd warm start: a resting column needs almost no iterations once its impulses are cached", "[nscd]") {
  const std::string solver = GENERATE("nlgs", "mprgp");
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  for (int k = 0; k < 10; ++k) s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 0.5 + k)));
  auto b = nscd::makeNscdBackend(s, {{"solver", solver}, {"tolerance", 1e-8}, {"max_iterations", 100000}});
  b->step(1e-3);
  const int cold = b->profile().iterations;
  // The first answer is only as converged as the stopping rule allows; a few warm steps finish it.
  for (int k = 0; k < 5; ++k) b->step(1e-3);
  const int warm = b->profile().iterations;
  b->step(2e-3);  // a different dt: cached impulses are rescaled to the new step
  const int rescaled = b->profile().iterations;
  INFO(solver << ": iterations cold " << cold << ", warm " << warm << ", rescaled " << rescaled);
  // From zero, a chain of 10 is slow for Gauss-Seidel; conjugate gradients need about one
  // iteration per distinct eigenvalue of the 10 x 10 Delassus matrix (plus the steps that free
  // the bounds).
  CHECK(cold > (solver == "nlgs" ? 50 : 10));
  CHECK(warm <= 3);
  CHECK(rescaled <= 3);
  CHECK(b->profile().residual < 1e-8);
  CHECK(b->profile().contactPoints == 10);
}

TEST_CASE("nscd pinacoid pairs: face on face is Triple, edge on face is Double", "[nscd]") {
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  // The lower pinacoid lies on a trapezoid face: 45 degrees about x brings the face normal
  // (0, -1, -1)/sqrt(2) onto -z, and the opposite face (0, 1, 1)/sqrt(2) onto +z.
  const core::Quat onFace(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, onFace), 0.0));
  const double top = topOf(s.grains[0]);
  SECTION("face on face") {
    s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, onFace),
                                    top));  // same orientation: its lower face on the top face
  }
  SECTION("edge on face") {
    // Identity orientation: the lower ridge (an edge along x) points down onto the top face.
    s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, core::Quat::Identity()), top));
  }
  const bool faceOnFace = s.grains[1].orientation.isApprox(onFace);
  auto b = nscd::makeNscdBackend(s, {{"tolerance", 1e-10}});
  b->step(1e-3);
  const core::Contact* pair = nullptr;
  for (const auto& c : b->contacts())
    if (c.b == 1) pair = &c;
  REQUIRE(pair != nullptr);
  CHECK(pair->a == 0);
  CHECK(pair->normal.z() == Approx(1.0).margin(1e-9));
  if (faceOnFace) {
    CHECK(pair->type == core::ContactType::Triple);
    CHECK(pair->points.size() >= 3);
  } else {
    CHECK(pair->type == core::ContactType::Double);
    CHECK(pair->points.size() == 2);
  }
  // The upper pinacoid's weight goes through the pair: its total force is m g (it is at rest).
  CHECK(pair->normalForce() == Approx(s.grains[1].volume()).epsilon(1e-6));
}

TEST_CASE("nscd determinism: a fixed-seed run hashes to a constant", "[nscd]") {
  // 24 polydisperse spheres dropped from a jittered lattice between frictional walls, 400 steps.
  // EXPECTED_HASH changes only in a commit that says why (a deliberate change of the numerics).
  core::SystemDef s = boxSystem(5.0, 3.0, false, 0.0);
  s.walls.friction = 0.3;
  core::Rng rng(99, core::StreamId::Test);
  for (int k = 0; k < 24; ++k)
    s.grains.push_back(sphere(rng.uniform(0.8, 1.0), Vec3(0.6 + 1.25 * (k % 4) + rng.uniform(-0.05, 0.05),
                                                          0.75 + 1.5 * ((k / 4) % 2) + rng.uniform(-0.1, 0.1),
                                                          0.6 + 1.1 * (k / 8) + rng.uniform(0.0, 0.05))));
  // Both solvers: Gauss-Seidel (rows, friction in the same visit) and MPRGP (blocked sums, body
  // rows, block Gauss-Seidel with the wall friction).
  const std::string solver = GENERATE("nlgs", "mprgp");
  const nlohmann::json options = {{"solver", solver}};
  auto b = nscd::makeNscdBackend(s, options);
  for (int k = 0; k < 400; ++k) b->step(2e-3);
  // FNV-1a over the bytes of every position and velocity component.
  testing::Fnv1a hash;
  auto mix = [&](double v) { hash.mix(v); };
  for (const auto& st : b->states())
    for (int i = 0; i < 3; ++i) {
      mix(st.position[i]);
      mix(st.velocity[i]);
    }
  // Changed from 0x42aada79cb35fc08 when the solver started sweeping rows bottom to top (sorted by
  // contact height) instead of in contact order: same law, different Gauss-Seidel iterates.
  // The MPRGP hash was set when that solver was added, and changed from 0x26dbf7a2eaef0688 when its
  // conjugate gradients became preconditioned by symmetric Gauss-Seidel sweeps: same law and
  // tolerance, different iterates; and from 0xdcf959b509b6c4ac when MPRGP started applying the
  // warm start's normal impulses itself, body by body (the same sums in another order).
  const std::uint64_t expected = solver == "nlgs" ? 0x95d29e41f7103684ull : 0xd0dca2990908874aull;
  INFO(solver);
  CHECK(hash.value == expected);
  // The same run twice gives the same bits (no hidden state, no uninitialised memory).
  auto again = nscd::makeNscdBackend(s, options);
  for (int k = 0; k < 400; ++k) again->step(2e-3);
  for (std::size_t i = 0; i < s.grains.size(); ++i) CHECK(again->states()[i].position == b->states()[i].position);
}

TEST_CASE("nscd mprgp: two threads give the bits of one on a pile large enough for its parallel passes", "[nscd]") {
  // 1,500 spheres of a geometric deposit, each given its placeholder's diameter so that they touch
  // at once (seated on three supports each): more than the 4,096 unknowns from which the solver's
  // passes run in parallel (mprgp_solver.cpp).
  const core::SystemDef s = touchingSpheres(14.0, 14.0, true, 1500, 5);
  core::SystemDef onTwo = s;
  onTwo.threads = 2;
  auto one = nscd::makeNscdBackend(s, {{"max_iterations", 30}});
  auto two = nscd::makeNscdBackend(onTwo, {{"max_iterations", 30}});
  for (int k = 0; k < 4; ++k) {
    one->step(2e-3);
    two->step(2e-3);
  }
  INFO("rows " << one->profile().contactPoints << ", iterations " << one->profile().iterations);
  REQUIRE(one->profile().contactPoints > 4096);
  REQUIRE(one->profile().iterations > 10);
  std::size_t different = 0;
  for (std::size_t i = 0; i < s.grains.size(); ++i)
    different += one->states()[i].position != two->states()[i].position ||
                 one->states()[i].velocity != two->states()[i].velocity;
  CHECK(different == 0);
  REQUIRE(one->contacts().size() == two->contacts().size());
  for (std::size_t c = 0; c < one->contacts().size(); ++c)
    CHECK(one->contacts()[c].normalForce() == two->contacts()[c].normalForce());
}

TEST_CASE("nscd mprgp: a column of face-on-face pinacoids carries k m g at its k-th contact", "[nscd]") {
  // Rows with lever arms across their normals (three points per face-on-face contact, sharing
  // bodies) take the angular path of the operator and of the preconditioner's sweeps. At rest on
  // the floor, the k-th contact from the top carries the weight of the k grains above it.
  const std::string preconditioner = GENERATE("sgs", "none", "cholesky");
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  const core::Quat onFace(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  constexpr int kColumn = 5;
  double bottom = 0.0;
  for (int k = 0; k < kColumn; ++k) {
    s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, onFace), bottom));
    bottom = topOf(s.grains.back());
  }
  auto b = nscd::makeNscdBackend(s, {{"tolerance", 1e-10}, {"preconditioner", preconditioner}});
  b->step(1e-3);
  INFO(preconditioner);
  const double weight = s.grains[0].volume();  // m g with rho = g = 1
  int seen = 0;
  for (const core::Contact& c : b->contacts()) {
    const int above = c.b >= 0 ? kColumn - c.b : kColumn;  // c.b < 0: the floor under grain 0
    INFO("contact " << c.a << "-" << c.b << ", points " << c.points.size());
    CHECK(c.points.size() >= 3);
    CHECK(c.normalForce() == Approx(above * weight).epsilon(1e-6));
    ++seen;
  }
  CHECK(seen == kColumn);
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

TEST_CASE(
    "nscd: a pressed pinacoid pile between rough walls, warm started on 2 threads, is bitwise the "
    "single-thread run",
    "[nscd][threads]") {
  // Grown by half, the grains overlap their neighbours from the first step: thousands of rows
  // (angular, multi-point, wall friction), so that the solver's passes run on the team, and the
  // later steps are warm started from the cache.
  requireSameRun(pile(core::ShapeKind::Pinacoid, 28.0, 5.0, 3000, 1.5), 3, 2e-3, true);
}
