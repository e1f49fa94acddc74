// The quasi-static finisher (compaction/quasi_static_finisher.hpp) on nscd, against static equilibria
// known in closed form: the finisher must end at the exact resting pose with the exact forces.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "backends/bullet/bullet_backend.hpp"
#include "backends/nscd/nscd_backend.hpp"
#include "compaction/quasi_static_finisher.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using core::Vec3;
using testing::boxSystem;
using testing::pinacoid;
using testing::sphere;
using testing::withBottomAt;

namespace {

/// Finisher steps on `b` until the last one moved nothing more than 1e-12 d_L; returns the finisher.
/// `largestMove`, if given, receives the largest displacement of any step.
compaction::QuasiStaticFinisher settle(core::ContactBackend& b, long maxSteps = 400, double* largestMove = nullptr) {
  core::CompactionDef def;
  def.settleTolerance = 1e-12;
  compaction::QuasiStaticFinisher f(def, 1.0, 1e-3);
  while (f.steps() < maxSteps && !(f.steps() > 1 && f.settled())) {
    const double moved = f.step(b).maxDisplacement;
    if (largestMove) *largestMove = std::max(*largestMove, moved);
  }
  return f;
}

double totalForceOn(const core::ContactBackend& b, int grain, int other) {
  double f = 0.0;
  for (const core::Contact& c : b.contacts())
    if ((c.a == grain && c.b == other) || (c.a == other && c.b == grain)) f += c.normalForce();
  return f;
}

const nlohmann::json kTight = {{"tolerance", 1e-12}};

}  // namespace

TEST_CASE("finisher: a sphere ends touching the floor with its centre at d/2, carrying m g", "[nscd][finisher]") {
  // From a gap inside the alert band, from far above (the trust radius cuts the steps), and from
  // an overlap: the same exact rest.
  const double start = GENERATE(0.52, 0.8, 0.497);
  core::SystemDef s = boxSystem(4.0, 4.0, false, 0.0);
  s.grains.push_back(sphere(1.0, Vec3(2.0, 2.0, start)));
  auto b = nscd::makeNscdBackend(s, kTight);
  double largestMove = 0.0;
  const compaction::QuasiStaticFinisher f = settle(*b, 400, &largestMove);
  INFO("start " << start << ", steps " << f.steps());
  CHECK(f.settled());
  CHECK(b->states()[0].position.z() == Approx(0.5).margin(1e-10));
  CHECK(b->states()[0].position.x() == Approx(2.0).margin(1e-12));
  CHECK(totalForceOn(*b, 0, -1) == Approx(s.grains[0].volume()).epsilon(1e-9));
  // No step moves a grain more than the trust radius (0.01 d): a fall of 0.3 d takes 30 steps.
  CHECK(largestMove <= core::CompactionDef{}.trustRadius);
  if (start == 0.8) CHECK(f.steps() >= 30);
}

TEST_CASE("finisher: a column of N beads carries k m g at its k-th contact from the top", "[nscd][finisher]") {
  constexpr int kBeads = 6;
  core::SystemDef s = boxSystem(4.0, 4.0, false, 0.0);
  for (int k = 0; k < kBeads; ++k) s.grains.push_back(sphere(1.0, Vec3(2.0, 2.0, 0.51 + 1.01 * k)));
  const std::string solver = GENERATE("ipm", "mprgp");  // the finisher's two solvers
  INFO("finisher_solver " << solver);
  nlohmann::json options = kTight;
  options["finisher_solver"] = solver;
  auto b = nscd::makeNscdBackend(s, options);
  REQUIRE(settle(*b).settled());
  const double weight = s.grains[0].volume();
  for (int k = 0; k < kBeads; ++k) {
    INFO("bead " << k);
    CHECK(b->states()[k].position.z() == Approx(0.5 + k).margin(1e-9));
    const int below = k == 0 ? -1 : k - 1;
    CHECK(totalForceOn(*b, k, below) == Approx((kBeads - k) * weight).epsilon(1e-9));
  }
}

TEST_CASE("finisher: a sphere in the groove of two spheres against the walls", "[nscd][finisher]") {
  // Walls at y = 0 and 2, two unit spheres on the floor against them and a third on top of both.
  // The top one rests at z = 1/2 + sqrt(3)/2 on two contacts at 60 degrees: each carries
  // m g / sqrt(3); each lower sphere pushes its wall with m g / (2 sqrt(3)) and the floor with
  // 3 m g / 2. The walls are frictionless (the floor always is).
  core::SystemDef s = boxSystem(3.0, 2.0, false, 0.0);
  s.grains.push_back(sphere(1.0, Vec3(1.5, 0.5, 0.505)));
  s.grains.push_back(sphere(1.0, Vec3(1.5, 1.5, 0.505)));
  s.grains.push_back(sphere(1.0, Vec3(1.5, 1.0, 0.52 + std::sqrt(0.75))));
  auto b = nscd::makeNscdBackend(s, kTight);
  REQUIRE(settle(*b).settled());
  const double mg = s.grains[0].volume();
  CHECK(b->states()[2].position.z() == Approx(0.5 + std::sqrt(0.75)).margin(1e-9));
  CHECK(b->states()[2].position.y() == Approx(1.0).margin(1e-9));
  CHECK(b->states()[0].position.y() == Approx(0.5).margin(1e-9));
  CHECK(b->states()[1].position.y() == Approx(1.5).margin(1e-9));
  for (int lower : {0, 1}) {
    INFO("lower sphere " << lower);
    CHECK(totalForceOn(*b, 2, lower) == Approx(mg / std::sqrt(3.0)).epsilon(1e-8));
    CHECK(totalForceOn(*b, lower, lower == 0 ? -2 : -3) == Approx(mg / (2.0 * std::sqrt(3.0))).epsilon(1e-8));
    CHECK(totalForceOn(*b, lower, -1) == Approx(1.5 * mg).epsilon(1e-8));
  }
}

TEST_CASE("finisher: a sphere rolling down a frictional wall moves only as far as its centre", "[nscd][finisher]") {
  // Sphere B leans on the side wall y = 0 (mu_w = 0.5) and on sphere A, which stands on the
  // frictionless floor 1/2 d further out: A's contact pushes B into the wall, A slides away and B
  // comes down the wall, rolling, since friction holds its contact point. A step's move is the
  // largest motion of a grain's surface, and a sphere's spin moves none of its surface: the move
  // must be the largest centre displacement, not that plus B's |w| r.
  core::SystemDef s = boxSystem(4.0, 4.0, false, 0.5);
  s.grains.push_back(sphere(1.0, Vec3(2.0, 1.0, 0.5001)));
  s.grains.push_back(sphere(1.0, Vec3(2.0, 0.5001, 0.5003 + std::sqrt(0.75))));
  auto b = nscd::makeNscdBackend(s, kTight);
  const Vec3 a0 = b->states()[0].position, b0 = b->states()[1].position;
  const core::QuasiStaticMove move = b->quasiStaticStep(0.2, 100.0);  // a trust radius that cuts nothing
  const Vec3 da = b->states()[0].position - a0, db = b->states()[1].position - b0;
  const double turned = core::Quat(b->states()[1].orientation).angularDistance(core::Quat::Identity());
  INFO("A moved " << da.transpose() << ", B moved " << db.transpose() << ", B turned " << turned);
  REQUIRE(da.y() > 1e-4);                    // A slid away from the wall
  REQUIRE(db.z() < -1e-4);                   // B came down
  REQUIRE(turned > 0.5 * std::abs(db.z()));  // and rolled: its spin is of the order of its fall / r
  CHECK_FALSE(move.clipped);
  CHECK(move.maxDisplacement == Approx(std::max(da.norm(), db.norm())).epsilon(1e-12));
}

TEST_CASE("finisher: a tilted pinacoid falls flat on a trapezoid face, the floor carrying m g", "[nscd][finisher]") {
  // 45 degrees about x lays a unit pinacoid on a trapezoid face; its centroid then sits at
  // G E / (2 sqrt(G^2 + E^2)) = 1 / (2 sqrt 2). Started 5 degrees off and 0.01 d up, it must
  // rotate back onto the face (a frictionless floor gives it no horizontal force).
  const core::Quat onFace(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  const core::Quat tilted(Eigen::AngleAxisd(std::numbers::pi / 4.0 + 5.0 * std::numbers::pi / 180.0, Vec3::UnitX()));
  core::SystemDef s = boxSystem(4.0, 4.0, false, 0.0);
  s.grains.push_back(withBottomAt(pinacoid(1.0, {2.0, 2.0, 0.0}, tilted), 0.01));
  REQUIRE(withBottomAt(pinacoid(1.0, {2.0, 2.0, 0.0}, onFace), 0.0).position.z() ==
          Approx(1.0 / (2.0 * std::sqrt(2.0))).epsilon(1e-12));
  auto b = nscd::makeNscdBackend(s, kTight);
  REQUIRE(settle(*b, 1000).settled());
  const core::BodyState& st = b->states()[0];
  CHECK(st.position.z() == Approx(1.0 / (2.0 * std::sqrt(2.0))).margin(1e-9));
  CHECK(std::abs(st.orientation.dot(onFace)) == Approx(1.0).margin(1e-12));
  REQUIRE(b->contacts().size() == 1);
  CHECK(b->contacts()[0].type == core::ContactType::Triple);
  CHECK(b->contacts()[0].normalForce() == Approx(s.grains[0].volume()).epsilon(1e-9));
}

TEST_CASE(
    "finisher: a pinacoid pile whose MPRGP solves end at their cap falls back to the interior point and ends at rest",
    "[nscd][finisher]") {
  // Two pinacoids on the floor, a third across them, tilted. With MPRGP capped at 3 iterations
  // its finisher steps are inexact once the grains touch; "auto" then hands the rest of the
  // finisher to the interior-point method, and the pile must end at rest with the floor carrying
  // its weight.
  // An explicit "mprgp" keeps MPRGP whatever its solves reach, and so does "auto" between
  // frictional walls (there the interior point does worse).
  const core::Quat flat(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  const core::Quat tilted(Eigen::AngleAxisd(0.3, Vec3(1.0, 0.2, 0.0).normalized()));
  const auto [solver, wallFriction] =
      GENERATE(table<std::string, double>({{"auto", 0.0}, {"mprgp", 0.0}, {"auto", 0.3}}));
  INFO("finisher_solver " << solver << ", mu_w " << wallFriction);
  core::SystemDef s = boxSystem(6.0, 6.0, false, wallFriction);
  s.grains.push_back(withBottomAt(pinacoid(1.0, {2.4, 3.0, 0.0}, flat), 0.005));
  s.grains.push_back(withBottomAt(pinacoid(1.0, {3.6, 3.0, 0.0}, flat), 0.005));
  s.grains.push_back(withBottomAt(pinacoid(1.0, {3.0, 3.1, 0.0}, tilted), 0.75));
  nlohmann::json options = kTight;
  options["max_iterations"] = 3;
  options["finisher_solver"] = solver;
  auto b = nscd::makeNscdBackend(s, options);
  core::CompactionDef def;
  def.settleTolerance = 1e-12;
  compaction::QuasiStaticFinisher f(def, 1.0, 1e-3);
  // Until a solve ends at the cap (an inexact step), which it does once the grains touch.
  while (f.steps() < 200 && b->profile().iterations < 3) f.step(*b);
  REQUIRE(b->profile().iterations == 3);
  const nlohmann::json capped = b->saveState();
  const bool fallsBack = solver == "auto" && wallFriction == 0.0;
  CHECK(capped["finisher_fell_back"] == fallsBack);
  CHECK(b->finisherReport() ==
        nlohmann::json{{"solver", fallsBack ? "ipm" : "mprgp"}, {"switched_from_mprgp", fallsBack}});
  if (!fallsBack) return;
  // A resumed run keeps the interior-point method.
  auto resumed = nscd::makeNscdBackend(s, options);
  resumed->restoreState(capped);
  CHECK(resumed->saveState()["finisher_fell_back"] == true);
  CHECK(resumed->finisherReport()["solver"] == "ipm");
  while (f.steps() < 2000 && !(f.steps() > 1 && f.settled())) f.step(*b);
  INFO("steps " << f.steps());
  REQUIRE(f.settled());
  double floor = 0.0;
  for (const core::Contact& c : b->contacts())
    if (c.b == -1 || c.a == -1) floor += c.normalForce();
  double weight = 0.0;
  for (const core::Grain& g : s.grains) weight += g.volume();
  CHECK(floor == Approx(weight).epsilon(1e-8));
}

TEST_CASE("finisher: a backend without a quasi-static step says so", "[bullet][finisher]") {
  core::SystemDef s = boxSystem(4.0, 4.0, false, 0.0);
  s.grains.push_back(sphere(1.0, Vec3(2.0, 2.0, 0.5)));
  auto b = bullet::makeBulletBackend(s, nlohmann::json::object());
  CHECK_FALSE(b->hasQuasiStaticStep());
  CHECK_THROWS_AS(b->quasiStaticStep(1e-3, 0.005), std::logic_error);
}
