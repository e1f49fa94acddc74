// The interior-point solver (backends/nscd/ipm_solver.hpp) on one cold step's contact problem: a
// resting column and a bidisperse pyramid are stopped exactly with their exact impulses, and on
// piles of spheres and of pinacoids between rough walls it reaches the velocities of MPRGP, the
// other solver of the same problem; on pinacoid face contacts (more points than constraints) its
// polish ends the solve at round-off.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <thread>
#include <vector>

#include "tests/backends/nscd/nscd_problems.hpp"

using namespace confpack;
using core::Vec3;
using testing::ColdStep;

namespace {

nscd::NscdSettings ipm(double tolerance = 1e-12) {
  nscd::NscdSettings s = nscd::defaultsFor(nscd::SolverKind::Ipm);
  s.tolerance = tolerance;
  return s;
}

/// A cold step of `s` with at least `minFaces` contacts of 4 points or more (pinacoid faces, each
/// with more points than the 3 constraints it can carry): `settings`' interior point solves it to
/// 1e-12 and reaches MPRGP's velocities.
void checkFaceContactSolve(const core::SystemDef& s, const nscd::NscdSettings& settings, std::size_t minFaces) {
  nscd::NscdSettings mprgp;
  mprgp.tolerance = 1e-12;
  const ColdStep a(s, settings), b(s, mprgp);
  std::size_t faces = 0;
  for (const nscd::ContactGeometry& g : a.contacts) faces += g.pointCount >= 4;
  INFO("rows " << a.solver.rowCount() << ", contacts " << a.contacts.size() << ", of 4 points or more " << faces
               << ", ipm iterations " << a.iterations << ", residual " << a.solver.residual());
  REQUIRE(faces >= minFaces);
  CHECK(a.solver.residual() < 1e-12);
  const auto [largest, difference] = testing::compareVelocities(a, b);
  INFO("largest velocity " << largest << ", largest difference " << difference);
  CHECK(difference < 1e-6 * ColdStep::kDt);
}

}  // namespace

TEST_CASE("nscd ipm: a column of touching beads is stopped dead, its k-th contact from the top carrying k m g dt",
          "[nscd]") {
  testing::checkBeadColumn(ipm(), 6, 1e-12);
}

TEST_CASE(
    "nscd ipm: a bidisperse pyramid is stopped dead, each small sphere carried by its two contacts at "
    "m_S g dt / (2 cos theta)",
    "[nscd]") {
  testing::checkBidispersePyramid(ipm(), 1e-10);
}

TEST_CASE("nscd ipm: on a touching sphere pile it reaches the velocities MPRGP reaches, in a few dozen iterations",
          "[nscd]") {
  // The velocities after the step are unique (see the MPRGP expansions test): two algorithms
  // must meet there. The interior-point iterations do not grow with the conditioning.
  const core::SystemDef s = testing::touchingSpheres(6.0, 6.0, false, 250, 7);
  nscd::NscdSettings mprgp;
  mprgp.tolerance = 1e-12;
  const ColdStep a(s, ipm()), b(s, mprgp);
  INFO("rows " << a.solver.rowCount() << ", ipm iterations " << a.iterations << ", mprgp iterations " << b.iterations);
  REQUIRE(a.solver.rowCount() > 250);
  CHECK(a.solver.residual() < 1e-12);
  CHECK(a.iterations < 60);
  const auto [largest, difference] = testing::compareVelocities(a, b);
  INFO("largest velocity " << largest << ", largest difference " << difference);
  CHECK(largest > 0.5 * ColdStep::kDt);  // not a trivial solution
  CHECK(difference < 1e-7 * largest);
}

TEST_CASE("nscd ipm: on a pressed pinacoid pile between walls with friction it reaches MPRGP's velocities", "[nscd]") {
  // Rotations (6 unknowns per grain) and side-wall friction (the block Gauss-Seidel with the
  // tangential passes) both in play: grown pinacoids press on each other and on the rough walls.
  const core::SystemDef s = testing::pile(core::ShapeKind::Pinacoid, 6.0, 3.0, 80, 1.4);
  nscd::NscdSettings mprgp;
  mprgp.tolerance = 1e-10;
  const ColdStep a(s, ipm(1e-10)), b(s, mprgp);
  INFO("rows " << a.solver.rowCount() << ", ipm iterations " << a.iterations << ", mprgp iterations " << b.iterations);
  REQUIRE(a.solver.rowCount() > 40);
  CHECK(a.solver.residual() < 1e-10);
  const auto [largest, difference] = testing::compareVelocities(a, b);
  INFO("largest velocity " << largest << ", largest difference " << difference);
  CHECK(largest > 0.1 * ColdStep::kDt);
  CHECK(difference < 1e-5 * largest);
}

TEST_CASE("nscd ipm: a pinacoid stack's face contacts, redundant points and all, solved to 1e-12", "[nscd]") {
  // Pinacoids lying on trapezoid faces, in a row on the floor and a second layer across the
  // joints, off their centres: each face contact carries 4 points for 3 constraints, so the
  // closed contacts' Delassus matrix is singular, and the polish that ends the solve must still
  // share each face's load between its points without negative impulses (ipm_solver.cpp). This
  // small cold step the polish solved before its proximal sweeps too; the finisher steps of large
  // piles where it did not are measured in docs/performance.md ("The interior point's polish").
  const core::Quat flat(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  core::SystemDef s = testing::boxSystem(8.0, 4.0, false, 0.0);
  for (int k = 0; k < 4; ++k)
    s.grains.push_back(testing::withBottomAt(testing::pinacoid(1.0, {1.5 + 1.05 * k, 2.0, 0.0}, flat), 0.0));
  const double top = s.grains[0].position.z() * 2.0;
  for (int k = 0; k < 3; ++k)
    s.grains.push_back(testing::withBottomAt(testing::pinacoid(1.0, {2.1 + 1.05 * k, 2.15, 0.0}, flat), top));
  checkFaceContactSolve(s, ipm(1e-12), 4);
}

TEST_CASE("nscd ipm: a brick wall of pinacoids, loaded off their faces' centres, ended exactly by the polish",
          "[nscd]") {
  // Eight courses of flat pinacoids, each course shifted half a brick along x and 0.3 across from
  // the one below: every face contact carries 4 points for 3 constraints, loaded off the face's
  // centre, so the least impulses that close the contacts make some points pull. The polish
  // started from zero then opens too many contacts a round and starts again from the interior
  // point's positive split (ipm_solver.cpp). With the interior point stopped after 8 iterations,
  // the polish must end the solve; from zero only, it stopped near 5e-6.
  const core::Quat flat(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  constexpr int kCourses = 8;
  constexpr int kBricks = 8;
  core::SystemDef s = testing::boxSystem(1.05 * kBricks + 3.0, 4.0, false, 0.0);
  double bottom = 0.0;
  for (int course = 0; course < kCourses; ++course) {
    const int shifted = course % 2;
    for (int k = 0; k < kBricks - shifted; ++k) {
      const Vec3 centre{1.5 + 0.6 * shifted + 1.05 * k, 2.0 + 0.3 * shifted, 0.0};
      s.grains.push_back(testing::withBottomAt(testing::pinacoid(1.0, centre, flat), bottom));
    }
    bottom = 2.0 * s.grains.back().position.z() - bottom;  // the course's top
  }
  nscd::NscdSettings capped = ipm(1e-12);
  capped.maxIterations = 8;
  checkFaceContactSolve(s, capped, 100);
}

// CHOLMOD's factorisations call BLAS, and a serial OpenBLAS is not safe to call from two threads
// at once: two runs of a sweep (`--jobs 2`) solving at the same time must each get the bits of a
// solve alone.
TEST_CASE("nscd ipm: solves in two threads at once give the bits of a solve alone", "[nscd]") {
  const core::SystemDef s = testing::touchingSpheres(12.0, 12.0, false, 1500, 11);
  const ColdStep alone(s, ipm());
  REQUIRE(alone.solver.rowCount() > 1500);
  for (int round = 0; round < 3; ++round) {
    std::vector<std::unique_ptr<ColdStep>> steps(2);
    std::vector<std::thread> threads;
    for (auto& step : steps) threads.emplace_back([&] { step = std::make_unique<ColdStep>(s, ipm()); });
    for (std::thread& t : threads) t.join();
    for (const auto& step : steps) {
      INFO("round " << round);
      REQUIRE(step->iterations == alone.iterations);
      for (std::size_t i = 0; i < alone.velocities.size(); ++i) {
        REQUIRE(step->velocities[i].v == alone.velocities[i].v);
        REQUIRE(step->velocities[i].w == alone.velocities[i].w);
      }
    }
  }
}
