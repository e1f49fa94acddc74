// The nonlinear Gauss-Seidel solver (backends/nscd/nlgs_solver.hpp) on one cold step's contact
// problem: a resting column is stopped exactly, and on a pile it reaches the velocities of the
// other solver of the same problem (MPRGP).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "backends/nscd/nlgs_solver.hpp"
#include "tests/backends/nscd/nscd_problems.hpp"

using namespace confpack;
using core::Vec3;
using testing::ColdStep;

namespace {

nscd::NscdSettings tightNlgs() {
  nscd::NscdSettings s;
  s.solver = nscd::SolverKind::Nlgs;
  s.tolerance = 1e-12;
  s.maxIterations = 100000;
  return s;
}

}  // namespace

TEST_CASE("nscd nlgs: a column of touching beads on the floor is stopped dead, each contact carrying the weight above",
          "[nscd]") {
  // Gravity gives every bead -g dt; the contacts (zero gaps) must take it all back: the only
  // velocities that satisfy Signorini for a resting chain are zero.
  core::SystemDef s = testing::boxSystem(5.0, 5.0, false, 0.0);
  constexpr int kBeads = 6;
  for (int k = 0; k < kBeads; ++k) s.grains.push_back(testing::sphere(1.0, Vec3(2.5, 2.5, 0.5 + k)));
  const ColdStep step(s, tightNlgs());
  REQUIRE(step.contacts.size() == kBeads);  // floor + 5 pairs
  CHECK(step.iterations > 0);
  CHECK(step.solver.residual() < 1e-12);
  CHECK(testing::largestSpeed(step) < 1e-9 * ColdStep::kDt);
}

TEST_CASE("nscd nlgs: on a touching pile it reaches the velocities MPRGP reaches", "[nscd]") {
  // Both solve the same frictionless problem, whose velocities are unique (see the MPRGP
  // expansions test): two different algorithms must meet there.
  const core::SystemDef s = testing::touchingSpheres(4.0, 4.0, false, 40, 3);
  nscd::NscdSettings mprgp;
  mprgp.tolerance = 1e-12;
  const ColdStep a(s, tightNlgs()), b(s, mprgp);
  INFO("rows " << a.solver.rowCount() << ", nlgs sweeps " << a.iterations << ", mprgp iterations " << b.iterations);
  REQUIRE(a.solver.rowCount() > 40);
  const auto [largest, difference] = testing::compareVelocities(a, b);
  INFO("largest velocity " << largest << ", largest difference " << difference);
  CHECK(largest > 0.5 * ColdStep::kDt);  // not a trivial solution
  CHECK(difference < 1e-6 * largest);
}
