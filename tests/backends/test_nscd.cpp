// Tests specific to the native contact dynamics backend (the conformance suite covers what both
// backends share).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <tuple>

#include <Eigen/Eigenvalues>

#include "backends/nscd/broad_phase.hpp"
#include "backends/nscd/contact_solver.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_backend.hpp"
#include "core/deposition.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "core/random.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using core::Vec3;

namespace {

using confpack::testing::pinacoid;
using confpack::testing::sphere;
using confpack::testing::topOf;

core::SystemDef box(double lx, double w, bool periodicY = false) {
  core::SystemDef s;
  s.box.lengthX = lx;
  s.box.width = w;
  s.box.periodicY = periodicY;
  return s;
}

/// Spheres that touch at once: a geometric deposit of `count` grains, each given its
/// placeholder's diameter (so seated on three supports or the floor).
core::SystemDef touchingSpheres(double lx, double w, bool periodicY, std::size_t count, std::uint64_t seed) {
  core::SystemDef s = box(lx, w, periodicY);
  core::DepositionDef def;
  def.grainCount = count;
  const core::Deposit dep = core::deposit(s.box, core::PopulationDef{}, def, seed);
  s.grains = dep.grains;
  for (core::Grain& g : s.grains) g.size = dep.placeholderDiameter;
  return s;
}

/// One step's contact problem of the grains of `s` at rest, solved cold (no warm start) with
/// `settings`: contacts from the broad and narrow phases at the grains' positions, inverse masses
/// (the last body is the static walls), velocities kicked by gravity over dt = 2e-3 and then
/// corrected by the solve.
struct ColdStep {
  static constexpr double kDt = 2e-3;
  std::vector<nscd::BodyInverseMass> bodies;
  std::vector<nscd::BodyVelocity> velocities;
  std::vector<nscd::ContactGeometry> contacts;
  nscd::ContactSolver solver;
  int iterations = 0;

  ColdStep(const core::SystemDef& s, const nscd::NscdSettings& settings)
      : bodies(s.grains.size() + 1), velocities(s.grains.size() + 1) {
    nscd::NarrowPhase narrow(s.box, s.grains, settings.alertDistance);
    nscd::BroadPhase broad(s.box, narrow.maxReach());
    std::vector<Vec3> positions;
    std::vector<core::Quat> orientations;
    std::vector<double> reach;
    for (std::size_t i = 0; i < s.grains.size(); ++i) {
      const core::Grain& g = s.grains[i];
      positions.push_back(g.position);
      orientations.push_back(g.orientation);
      reach.push_back(narrow.reach(static_cast<int>(i)));
      bodies[i].invMass = 1.0 / (s.density * g.volume());
      bodies[i].invInertia = g.bodyInertia(s.density).inverse();
      velocities[i].v = Vec3(0.0, 0.0, -kDt);  // g = 1
    }
    std::vector<nscd::CandidatePair> pairs;
    broad.findPairs(positions, reach, pairs);
    narrow.collideAll(pairs, positions, orientations, contacts, 1);
    solver.prepare(contacts, positions, bodies, s.box, kDt, settings);
    solver.warmStart(nscd::ContactCache{}, contacts, kDt, velocities);
    iterations = solver.solve(velocities, settings);
  }
};

}  // namespace

TEST_CASE("nscd free fall error is (theta - 1/2) g t dt", "[nscd]") {
  // q_{i+1} = q_i + dt ((1 - theta) v_i + theta v_{i+1}) with v_k = -g k dt sums to
  // z_n = z0 - g dt^2 (n (n - 1)/2 + theta n) = z0 - g t^2/2 - (theta - 1/2) g t dt.
  const double theta = GENERATE(0.5, 0.75, 1.0);
  const double dt = GENERATE(2e-3, 1e-2);
  core::SystemDef s = box(20.0, 10.0);
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
    core::SystemDef s = box(20.0, 10.0);
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
    for (const nlohmann::json& options : {nlohmann::json::object(), nlohmann::json{{"damping", c}, {"damping_speed", 0.1 * fx * dt}}}) {
      auto free = nscd::makeNscdBackend(s, options);
      for (int k = 0; k < n; ++k) free->step(dt);
      CHECK(free->states()[0].velocity.x() == Approx(fx * n * dt).epsilon(1e-12));
    }
  }
  SECTION("free fall is exact: a grain without contact is not damped") {
    core::SystemDef s = box(20.0, 10.0);
    s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 100.0)));
    auto b = nscd::makeNscdBackend(s, {{"damping", c}});
    for (int k = 0; k < n; ++k) b->step(dt);
    const double t = n * dt;
    CHECK(b->states()[0].position.z() == Approx(100.0 - 0.5 * t * t).epsilon(1e-13));
  }
  SECTION("a resting column still carries k m g at its k-th contact") {
    core::SystemDef s = box(20.0, 10.0);
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

TEST_CASE("nscd options: defaults resolved, unknown keys and bad values refused by name", "[nscd]") {
  core::SystemDef s = box(20.0, 10.0);
  s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 0.5)));
  const nlohmann::json resolved = nscd::makeNscdBackend(s, nlohmann::json::object())->settings();
  for (const char* key : {"theta", "expansion", "preconditioner", "tolerance", "max_iterations", "min_iterations",
                          "alert_distance", "gap_correction", "max_correction_velocity", "damping", "damping_speed",
                          "threads"})
    CHECK(resolved.contains(key));
  CHECK(resolved["theta"] == 0.5);
  CHECK(resolved["tolerance"].get<double>() <= 1e-4);
  // The resolved settings round-trip: feeding them back gives the same settings.
  CHECK(nscd::makeNscdBackend(s, resolved)->settings() == resolved);
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"tolerence", 1e-6}}), Catch::Contains("tolerence"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"theta", 0.3}}), Catch::Contains("theta"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"max_iterations", 0}}), Catch::Contains("max_iterations"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"gap_correction", 1.5}}), Catch::Contains("gap_correction"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"damping", -0.1}}), Catch::Contains("damping"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"damping_speed", 0.0}}), Catch::Contains("damping_speed"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"tolerance", "small"}}), Catch::Contains("tolerance"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"expansion", "cg"}}), Catch::Contains("expansion"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"preconditioner", "ic"}}), Catch::Contains("preconditioner"));
  CHECK_THROWS_AS(nscd::makeNscdBackend(s, nlohmann::json::array()), std::invalid_argument);
  // A box too short for the grains' periodic images is refused, not silently wrong.
  core::SystemDef tiny = box(1.5, 10.0);
  tiny.grains.push_back(sphere(1.0, Vec3(0.5, 5.0, 0.5)));
  CHECK_THROWS_AS(nscd::makeNscdBackend(tiny, {}), std::invalid_argument);
  auto b = nscd::makeNscdBackend(s, {});
  CHECK_THROWS_AS(b->step(0.0), std::invalid_argument);
}

TEST_CASE("nscd broad phase finds exactly the pairs of a brute-force minimum-image search", "[nscd]") {
  const bool periodicY = GENERATE(false, true);
  core::BoxDef bx;
  bx.lengthX = 7.0;
  bx.width = 6.0;
  bx.periodicY = periodicY;
  core::Rng rng(5, core::StreamId::Test);
  std::vector<Vec3> p;
  std::vector<double> reach;
  for (int i = 0; i < 300; ++i) {
    // Some positions slightly outside the box, as the predicted configuration can be.
    p.emplace_back(rng.uniform(-0.1, bx.lengthX + 0.1), rng.uniform(0.0, bx.width), rng.uniform(0.0, 6.0));
    reach.push_back(rng.uniform(0.3, 0.55));
  }
  nscd::BroadPhase bp(bx, 0.55);
  std::vector<nscd::CandidatePair> pairs;
  bp.findPairs(p, reach, pairs);
  std::set<std::tuple<int, int, int, int>> found, expected;
  for (const auto& c : pairs) found.insert({c.a, c.b, c.shiftX, c.shiftY});
  for (int i = 0; i < 300; ++i)
    for (int j = i + 1; j < 300; ++j) {
      const Vec3 raw = p[j] - p[i];
      const Vec3 d = bx.minimumImage(raw);
      if (d.norm() >= reach[i] + reach[j]) continue;
      expected.insert({i, j, static_cast<int>(std::lround((d.x() - raw.x()) / bx.lengthX)),
                       static_cast<int>(std::lround((d.y() - raw.y()) / bx.width))});
    }
  CHECK(found.size() == pairs.size());  // no duplicates
  CHECK(found == expected);
  CHECK(expected.size() > 100);  // the test is not vacuous
}

TEST_CASE("nscd: a sphere falling on the floor stops dead at contact (no bounce, no overlap)", "[nscd]") {
  const double dt = GENERATE(1e-3, 5e-3);
  {
    core::SystemDef s = box(20.0, 10.0);
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
    CHECK(minGap > -1e-12);                // never below the floor
    CHECK(maxUp < 1e-12);                  // never moves up: e_n = 0
    CHECK(b->states()[0].velocity.norm() < 1e-12);
    CHECK(b->states()[0].position.z() == Approx(0.5).margin(1e-12));
  }
}

TEST_CASE("nscd: a small sphere dropped on a large one comes to rest on it and loads it", "[nscd]") {
  // e_n = 0: after the impact the small sphere sits on the large one; at rest the pair carries
  // the small weight and the floor both weights.
  core::SystemDef s = box(20.0, 10.0);
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
  core::SystemDef s = box(20.0, 10.0);
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
  core::SystemDef s = box(20.0, 10.0);
  // The lower pinacoid lies on a trapezoid face: 45 degrees about x brings the face normal
  // (0, -1, -1)/sqrt(2) onto -z, and the opposite face (0, 1, 1)/sqrt(2) onto +z.
  const core::Quat onFace(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  s.grains.push_back(pinacoid(onFace, 10.0, 5.0, 0.0));
  const double top = topOf(s.grains[0]);
  SECTION("face on face") {
    s.grains.push_back(pinacoid(onFace, 10.0, 5.0, top));  // same orientation: its lower face on the top face
  }
  SECTION("edge on face") {
    // Identity orientation: the lower ridge (an edge along x) points down onto the top face.
    s.grains.push_back(pinacoid(core::Quat::Identity(), 10.0, 5.0, top));
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
  core::SystemDef s = box(5.0, 3.0);
  s.box.wallFriction = 0.3;
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
  std::uint64_t hash = 1469598103934665603ull;
  auto mix = [&](double v) {
    unsigned char bytes[sizeof(double)];
    std::memcpy(bytes, &v, sizeof v);
    for (unsigned char c : bytes) hash = (hash ^ c) * 1099511628211ull;
  };
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
  CHECK(hash == expected);
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
  auto one = nscd::makeNscdBackend(s, {{"threads", 1}, {"max_iterations", 30}});
  auto two = nscd::makeNscdBackend(s, {{"threads", 2}, {"max_iterations", 30}});
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

TEST_CASE("nscd contact cache: entries given in any order are found by key, from any cursor", "[nscd]") {
  // Keys as the narrow phase makes them: grain pairs in key order, then wall contacts grain by
  // grain (floor -1 before side walls -2, -3: not key order), plus a shuffled variant.
  core::Rng rng(3, core::StreamId::DepositionXY);
  std::vector<nscd::CachedContact> pairs, walls;
  for (int a = 0; a < 200; ++a) {
    for (int b = a + 1; b < 200; ++b)
      if (rng.uniform(0.0, 1.0) < 0.03) pairs.push_back({{a, b, 0, 0, 0u}, 1, {rng.uniform(0.0, 1.0)}, {}, {}});
    for (int w : {-1, -2, -3})
      if (rng.uniform(0.0, 1.0) < 0.1) walls.push_back({{a, w, 0, 0, 0u}, 1, {rng.uniform(0.0, 1.0)}, {}, {}});
  }
  std::vector<nscd::CachedContact> all = pairs;
  all.insert(all.end(), walls.begin(), walls.end());
  const bool shuffled = GENERATE(false, true);
  std::vector<nscd::CachedContact> given = all;
  if (shuffled)
    for (std::size_t i = given.size() - 1; i > 0; --i) std::swap(given[i], given[rng.below(i + 1)]);
  nscd::ContactCache cache;
  std::vector<nscd::CachedContact> buffer = given;
  cache.replace(buffer, 1e-3);
  CHECK(buffer.empty());
  REQUIRE(cache.size() == all.size());
  // Look every key up in the given order (the warm start's), with one cursor, then in reverse.
  std::size_t cursor = 0, found = 0;
  for (const auto& order : {given, std::vector<nscd::CachedContact>(given.rbegin(), given.rend())})
    for (const nscd::CachedContact& e : order) {
      const nscd::CachedContact* hit = cache.find(e.key, cursor);
      REQUIRE(hit != nullptr);
      found += hit->key == e.key && hit->normal[0] == e.normal[0];
      CHECK(hit == cache.find(e.key));
    }
  CHECK(found == 2 * all.size());
  // Absent keys: a pair that is not there, a grain beyond the last, from either end.
  for (std::size_t start : {std::size_t{0}, all.size()}) {
    cursor = start;
    CHECK(cache.find({0, 0, 0, 0, 0u}, cursor) == nullptr);
    CHECK(cache.find({500, 501, 0, 0, 0u}, cursor) == nullptr);
  }
}

TEST_CASE("nscd mprgp: the preconditioner's two sweep blocks share no grain, and two threads sweep them to the bits of one",
          "[nscd]") {
  // Spheres (rows without lever arms across the normal) and pinacoids (angular rows, multi-point
  // contacts, side walls with friction), each in a box long enough for the rows to be split.
  const bool pinacoids = GENERATE(false, true);
  core::SystemDef s;
  if (pinacoids) {
    s = box(28.0, 5.0);
    s.box.wallFriction = 0.3;
    core::PopulationDef population;
    population.shape = core::ShapeKind::Pinacoid;
    core::DepositionDef def;
    def.grainCount = 3000;
    s.grains = core::deposit(s.box, population, def, 11).grains;
    // Placeholders circumscribe the grains: grown by half, neighbours overlap, as in a pile
    // pressed together (one cold step: overlaps only set the gap terms).
    for (core::Grain& g : s.grains) g.size *= 1.5;
  } else {
    s = touchingSpheres(14.0, 14.0, true, 1500, 5);
  }
  nscd::NscdSettings one;  // the defaults: MPRGP preconditioned by Gauss-Seidel
  one.maxIterations = 30;
  nscd::NscdSettings two = one;
  two.threads = 2;
  const ColdStep a(s, one), b(s, two);
  INFO("pinacoids " << pinacoids << ", rows " << a.solver.rowCount() << ", iterations " << a.iterations);
  // Enough rows for the solver to run on the team (its passes need 4,096 unknowns), and each
  // block a good part of the pile.
  REQUIRE(a.solver.rowCount() > 4096);
  const auto blocks = a.solver.sweepBlockBodies(static_cast<int>(s.grains.size()));
  CHECK(blocks[0].size() > s.grains.size() / 4);
  CHECK(blocks[1].size() > s.grains.size() / 4);
  std::vector<int> shared;
  std::set_intersection(blocks[0].begin(), blocks[0].end(), blocks[1].begin(), blocks[1].end(),
                        std::back_inserter(shared));
  CHECK(shared.empty());
  CHECK(a.iterations == b.iterations);
  std::size_t different = 0;
  for (std::size_t i = 0; i < s.grains.size(); ++i)
    different += a.velocities[i].v != b.velocities[i].v || a.velocities[i].w != b.velocities[i].w;
  CHECK(different == 0);
}

TEST_CASE("nscd mprgp: the bound of the scaled Delassus norm is its Gershgorin bound (spheres)", "[nscd]") {
  // MPRGP's expansion step alpha_bar = 1.95 / bound needs bound >= ||S W S|| (Dostal); the closer,
  // the longer the step. The bound must be the largest absolute row sum of S W S, formed here
  // densely from the contact normals and masses. Rows of a touching sphere network: a geometric
  // deposit with every grain given its placeholder's diameter (each seated on three supports or
  // the floor), sizes then shrunk by up to 2% so that masses differ and gaps stay within the alert
  // distance.
  core::SystemDef s = touchingSpheres(5.0, 5.0, false, 120, 3);
  core::Rng rng(5, core::StreamId::Test);
  for (core::Grain& g : s.grains) g.size *= 1.0 - 0.02 * rng.uniform();
  const int n = static_cast<int>(s.grains.size());
  const nscd::NscdSettings settings;  // mprgp
  ColdStep step(s, settings);
  const std::vector<nscd::BodyInverseMass>& bodies = step.bodies;
  const std::vector<nscd::ContactGeometry>& contacts = step.contacts;
  const nscd::ContactSolver& solver = step.solver;

  // ||S W S|| = largest eigenvalue of B^T B, B = M^-1/2 H S: column k holds -s_k m_a^-1/2 n_k on
  // grain a and +s_k m_b^-1/2 n_k on grain b (none on a wall), s_k = (1/m_a + 1/m_b)^-1/2.
  std::vector<std::tuple<int, int, Vec3>> rows;
  for (const auto& g : contacts)
    for (int p = 0; p < g.pointCount; ++p) rows.emplace_back(g.a, g.b, g.normal);
  Eigen::MatrixXd bMatrix = Eigen::MatrixXd::Zero(3 * n, static_cast<Eigen::Index>(rows.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto& [a, b, normal] = rows[k];
    const double wa = bodies[a].invMass, wb = b >= 0 ? bodies[b].invMass : 0.0;
    const double sk = 1.0 / std::sqrt(wa + wb);
    bMatrix.block<3, 1>(3 * a, static_cast<Eigen::Index>(k)) = -sk * std::sqrt(wa) * normal;
    if (b >= 0) bMatrix.block<3, 1>(3 * b, static_cast<Eigen::Index>(k)) = sk * std::sqrt(wb) * normal;
  }
  const Eigen::MatrixXd a = bMatrix.transpose() * bMatrix;
  const double exact = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  const double gershgorin = a.cwiseAbs().rowwise().sum().maxCoeff();
  INFO("rows " << rows.size() << ", exact " << exact << ", bound " << solver.operatorBound() << ", Gershgorin "
               << gershgorin);
  REQUIRE(rows.size() > 2 * static_cast<std::size_t>(n));  // a connected network, floor included
  CHECK(solver.operatorBound() >= exact);
  CHECK(solver.operatorBound() == Approx(gershgorin).epsilon(1e-12));
  CHECK(solver.operatorBound() < 2.0 * exact);  // 1.72 here
}

TEST_CASE("nscd mprgp: the projected-CG and Dostal expansions reach the same velocities", "[nscd]") {
  // Both expansions (NscdSettings::expansion) minimise the same quadratic program
  // 1/2 r.W r + r.(u_free + c) over r >= 0, W = H^T M^-1 H. Its minimisers all share W r (the
  // objective is convex and quadratic, so it is constant along the segment between two of them,
  // which forces (r1 - r2).W (r1 - r2) = 0), hence M^-1 H r: the grains' velocities after the step
  // are unique, whichever path reaches them. The pile must make both expansions run: touching
  // spheres, so that every grain is stopped by a network of active contacts.
  const core::SystemDef s = touchingSpheres(6.0, 6.0, false, 250, 7);
  // Tolerance 1e-12 on the relative projected gradient: near jamming a small residual still
  // allows a larger velocity error (W is ill-conditioned); at the default 1e-10 the two differ by
  // 7e-7 of the largest velocity, at 1e-12 by 8e-9.
  nscd::NscdSettings projected;
  projected.tolerance = 1e-12;
  nscd::NscdSettings gradient = projected;
  gradient.expansion = nscd::ExpansionKind::Gradient;
  const ColdStep a(s, projected), b(s, gradient);
  INFO("rows " << a.solver.rowCount() << "; iterations projected " << a.iterations << " (cg " << a.solver.mprgpSteps().conjugate
       << ", projected " << a.solver.mprgpSteps().projected << ", gradient " << a.solver.mprgpSteps().gradient
       << "), gradient " << b.iterations << " (cg " << b.solver.mprgpSteps().conjugate << ", gradient "
       << b.solver.mprgpSteps().gradient << ")");
  REQUIRE(a.solver.mprgpSteps().projected > 0);
  REQUIRE(b.solver.mprgpSteps().gradient > 0);
  CHECK(b.solver.mprgpSteps().projected == 0);
  CHECK(a.solver.residual() < projected.tolerance);
  CHECK(b.solver.residual() < gradient.tolerance);
  double largest = 0.0, difference = 0.0;
  for (std::size_t i = 0; i + 1 < a.velocities.size(); ++i) {
    largest = std::max(largest, a.velocities[i].v.norm());
    difference = std::max(difference, (a.velocities[i].v - b.velocities[i].v).norm());
  }
  INFO("largest velocity " << largest << ", largest difference " << difference);
  CHECK(largest > 0.5 * ColdStep::kDt);  // not a trivial solution
  CHECK(difference < 1e-7 * largest);
}

TEST_CASE("nscd mprgp: the Gauss-Seidel preconditioner reaches the plain solver's velocities in fewer iterations",
          "[nscd]") {
  // Preconditioning changes the path of the conjugate gradients on the free set, not the
  // quadratic program, whose minimisers all share the grains' velocities (previous test). The
  // preconditioned solve must reach them, and in fewer applications of W: the point of it.
  const core::SystemDef s = touchingSpheres(6.0, 6.0, false, 250, 7);
  nscd::NscdSettings plain;
  plain.tolerance = 1e-12;
  plain.preconditioner = nscd::PreconditionerKind::None;
  nscd::NscdSettings sgs = plain;
  sgs.preconditioner = nscd::PreconditionerKind::SymmetricGaussSeidel;
  const ColdStep a(s, sgs), b(s, plain);
  INFO("rows " << a.solver.rowCount() << "; iterations sgs " << a.iterations << ", none " << b.iterations);
  CHECK(a.solver.residual() < sgs.tolerance);
  CHECK(b.solver.residual() < plain.tolerance);
  CHECK(a.iterations < b.iterations);
  double largest = 0.0, difference = 0.0;
  for (std::size_t i = 0; i + 1 < a.velocities.size(); ++i) {
    largest = std::max(largest, a.velocities[i].v.norm());
    difference = std::max(difference, (a.velocities[i].v - b.velocities[i].v).norm());
  }
  INFO("largest velocity " << largest << ", largest difference " << difference);
  CHECK(largest > 0.5 * ColdStep::kDt);
  CHECK(difference < 1e-7 * largest);
}

TEST_CASE("nscd mprgp: a column of face-on-face pinacoids carries k m g at its k-th contact", "[nscd]") {
  // Rows with lever arms across their normals (three points per face-on-face contact, sharing
  // bodies) take the angular path of the operator and of the preconditioner's sweeps. At rest on
  // the floor, the k-th contact from the top carries the weight of the k grains above it.
  const std::string preconditioner = GENERATE("sgs", "none");
  core::SystemDef s = box(20.0, 10.0);
  const core::Quat onFace(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  constexpr int kColumn = 5;
  double bottom = 0.0;
  for (int k = 0; k < kColumn; ++k) {
    s.grains.push_back(pinacoid(onFace, 10.0, 5.0, bottom));
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
