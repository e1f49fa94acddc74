// The MPRGP contact solver (backends/nscd/mprgp_solver.hpp) on one cold step's contact problem:
// its preconditioner's blocks, its norm bound, the velocities its variants reach, and the exact
// impulses of a bead column and a bidisperse pyramid.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <iterator>
#include <set>
#include <vector>

#include "backends/nscd/mprgp_solver.hpp"
#include "tests/backends/nscd/nscd_problems.hpp"

using namespace confpack;
using core::Vec3;
using testing::boxSystem;
using testing::ColdStep;
using testing::touchingSpheres;

TEST_CASE(
    "nscd mprgp: the preconditioner's two sweep blocks share no grain, and two threads sweep them to the bits of one",
    "[nscd]") {
  // Spheres (rows without lever arms across the normal) and pinacoids (angular rows, multi-point
  // contacts, side walls with friction), each in a box long enough for the rows to be split.
  const bool pinacoids = GENERATE(false, true);
  core::SystemDef s;
  if (pinacoids) {
    s = boxSystem(28.0, 5.0, false, 0.0);
    s.walls.friction = 0.3;
    core::PopulationDef population;
    population.shape = core::ShapeKind::Pinacoid;
    core::DepositionDef def;
    def.grainCount = 3000;
    s.grains = compaction::deposit(s.box, population, def, 11).grains;
    // Placeholders circumscribe the grains: grown by half, neighbours overlap, as in a pile
    // pressed together (one cold step: overlaps only set the gap terms).
    for (core::Grain& g : s.grains) g.size *= 1.5;
  } else {
    s = touchingSpheres(14.0, 14.0, true, 1500, 5);
  }
  nscd::NscdSettings one;  // the defaults: MPRGP preconditioned by Gauss-Seidel
  one.maxIterations = 30;
  const ColdStep a(s, one, 1), b(s, one, 2);
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
  const double exact =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
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
  INFO("rows " << a.solver.rowCount() << "; iterations projected " << a.iterations << " (cg "
               << a.solver.mprgpSteps().conjugate << ", projected " << a.solver.mprgpSteps().projected << ", gradient "
               << a.solver.mprgpSteps().gradient << "), gradient " << b.iterations << " (cg "
               << b.solver.mprgpSteps().conjugate << ", gradient " << b.solver.mprgpSteps().gradient << ")");
  REQUIRE(a.solver.mprgpSteps().projected > 0);
  REQUIRE(b.solver.mprgpSteps().gradient > 0);
  CHECK(b.solver.mprgpSteps().projected == 0);
  CHECK(a.solver.residual() < projected.tolerance);
  CHECK(b.solver.residual() < gradient.tolerance);
  const auto [largest, difference] = testing::compareVelocities(a, b);
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
  const auto [largest, difference] = testing::compareVelocities(a, b);
  INFO("largest velocity " << largest << ", largest difference " << difference);
  CHECK(largest > 0.5 * ColdStep::kDt);
  CHECK(difference < 1e-7 * largest);
}

TEST_CASE("nscd mprgp: over-relaxed friction passes reach the velocities of plain ones", "[nscd]") {
  // friction_relaxation over-relaxes the tangential passes of the block iteration around side-wall
  // friction: it changes the path to the Coulomb law's solution, not the solution, and the solve
  // stops at the same tolerance, in fewer iterations (the point of it: 244 against 687 here).
  // Spheres that touch at once, against walls of mu_w = 0.5; the frictionless solve must differ,
  // or the test would not see friction at all.
  core::SystemDef s = touchingSpheres(6.0, 4.0, false, 200, 7);
  s.walls.friction = 0.5;
  nscd::NscdSettings plain;
  plain.tolerance = 1e-12;
  plain.frictionRelaxation = 1.0;
  nscd::NscdSettings relaxed = plain;
  relaxed.frictionRelaxation = 1.2;
  const ColdStep a(s, relaxed), b(s, plain);
  core::SystemDef frictionless = s;
  frictionless.walls.friction = 0.0;
  const ColdStep c(frictionless, plain);
  INFO("rows " << a.solver.rowCount() << "; iterations relaxed " << a.iterations << ", plain " << b.iterations);
  CHECK(a.solver.residual() < relaxed.tolerance);
  CHECK(b.solver.residual() < plain.tolerance);
  CHECK(a.iterations < b.iterations);
  const auto [largest, difference] = testing::compareVelocities(a, b);
  const double frictionEffect = testing::compareVelocities(a, c).difference;
  INFO("largest velocity " << largest << ", difference " << difference << ", against frictionless walls "
                           << frictionEffect);
  CHECK(largest > 0.5 * ColdStep::kDt);
  REQUIRE(frictionEffect > 1e-3 * largest);
  CHECK(difference < 1e-7 * largest);
}

TEST_CASE(
    "nscd mprgp: the exact free-block preconditioner reaches the Gauss-Seidel solver's velocities in fewer "
    "iterations",
    "[nscd]") {
  // "cholesky" preconditions the conjugate gradients with (A_FF + eps I)^-1 (free_block_inverse.hpp)
  // and searches along projected steps: another path to the same quadratic program's minimisers,
  // which share the grains' velocities. Spheres, spheres between walls with friction (rows on the
  // static world, the block iteration), and pinacoids (angular rows, a 6 x 6 mass block a grain).
  const int variant = GENERATE(0, 1, 2);
  core::SystemDef s;
  if (variant == 2) {
    s = boxSystem(7.0, 5.0, false, 0.0);
    core::PopulationDef population;
    population.shape = core::ShapeKind::Pinacoid;
    core::DepositionDef def;
    def.grainCount = 200;
    s.grains = compaction::deposit(s.box, population, def, 3).grains;
    for (core::Grain& g : s.grains) g.size *= 1.5;  // pressed together, as in the first test
  } else {
    s = touchingSpheres(6.0, 6.0, false, 250, 7);
    if (variant == 1) s.walls.friction = 0.5;
  }
  nscd::NscdSettings sgs;
  sgs.tolerance = 1e-12;
  nscd::NscdSettings exact = sgs;
  exact.preconditioner = nscd::PreconditionerKind::Cholesky;
  const ColdStep a(s, exact), b(s, sgs);
  INFO("variant " << variant << ", rows " << a.solver.rowCount() << "; iterations cholesky " << a.iterations
                  << " (factorisations " << a.solver.mprgpSteps().factorisations << ", updates "
                  << a.solver.mprgpSteps().factorUpdates << "), sgs " << b.iterations);
  CHECK(a.solver.residual() < exact.tolerance);
  CHECK(b.solver.residual() < sgs.tolerance);
  CHECK(a.solver.mprgpSteps().factorisations >= 1);
  if (variant != 1) CHECK(a.iterations < b.iterations);  // with friction both count the tangential passes
  const auto [largest, difference] = testing::compareVelocities(a, b);
  INFO("largest velocity " << largest << ", largest difference " << difference);
  CHECK(largest > 0.5 * ColdStep::kDt);
  CHECK(difference < 1e-7 * largest);
}

TEST_CASE(
    "nscd mprgp, switching: a solve past its sgs budget ends on cholesky at sgs's velocities, the next solves "
    "start on cholesky, and every 16th tries sgs again",
    "[nscd]") {
  const core::SystemDef s = touchingSpheres(6.0, 6.0, false, 250, 7);
  nscd::NscdSettings sgs;
  sgs.tolerance = 1e-12;
  nscd::NscdSettings switching = sgs;
  switching.preconditioner = nscd::PreconditionerKind::Switching;
  // A budget far above what sgs needs: the solve never leaves sgs, and is its solve to the bit.
  switching.preconditionerSwitch = 100.0;
  const ColdStep plain(s, sgs), generous(s, switching);
  CHECK(generous.iterations == plain.iterations);
  CHECK(generous.solver.mprgpSteps().factorisations == 0);
  CHECK(testing::compareVelocities(generous, plain).difference == 0.0);
  // A budget of a few iterations (0.02 a row): the first solve switches on its way.
  switching.preconditionerSwitch = 0.02;
  ColdStep step(s, switching);
  const int budget = static_cast<int>(0.02 * static_cast<double>(step.solver.rowCount()));
  INFO("rows " << step.solver.rowCount() << ", budget " << budget << ", sgs " << plain.iterations << ", switched "
               << step.iterations);
  REQUIRE(budget < plain.iterations);
  CHECK(step.solver.residual() < sgs.tolerance);
  CHECK(step.solver.mprgpSteps().factorisations >= 1);
  const auto [largest, difference] = testing::compareVelocities(step, plain);
  CHECK(largest > 0.5 * ColdStep::kDt);
  CHECK(difference < 1e-7 * largest);
  // The switched solve spent its budget on sgs first; the next 15 start on cholesky and take the
  // same (fewer) iterations each; the 16th spends the budget on sgs again.
  const int switched = step.iterations;
  std::vector<int> counts;
  for (int solve = 0; solve < nscd::kSwitchProbeInterval; ++solve) counts.push_back(step.solveAgain(switching));
  INFO("iterations of the next solves: " << Catch::Detail::stringify(counts));
  const int onCholesky = counts.front();
  CHECK(onCholesky < switched);
  CHECK(std::count(counts.begin(), counts.end() - 1, onCholesky) == nscd::kSwitchProbeInterval - 1);
  CHECK(counts.back() == switched);
  CHECK(step.solver.residual() < sgs.tolerance);
}

TEST_CASE(
    "nscd mprgp, cholesky: a column of touching beads is stopped dead, its k-th contact from the top carrying "
    "k m g dt",
    "[nscd]") {
  nscd::NscdSettings settings;
  settings.tolerance = 1e-12;
  settings.preconditioner = nscd::PreconditionerKind::Cholesky;
  const auto step = testing::checkBeadColumn(settings, 8, 1e-10);
  CHECK(step->solver.mprgpSteps().factorisations == 1);
}

TEST_CASE(
    "nscd mprgp: a bidisperse pyramid is stopped dead, each small sphere carried by its two contacts at "
    "m_S g dt / (2 cos theta), with each preconditioner",
    "[nscd]") {
  // Unequal masses and an oblique load: the Delassus rows differ in scale, which the Jacobi
  // scaling and each preconditioner must leave the same unique impulses.
  const auto preconditioner = GENERATE(nscd::PreconditionerKind::SymmetricGaussSeidel, nscd::PreconditionerKind::None,
                                       nscd::PreconditionerKind::Cholesky, nscd::PreconditionerKind::Switching);
  nscd::NscdSettings settings;
  settings.tolerance = 1e-12;
  settings.preconditioner = preconditioner;
  INFO("preconditioner " << static_cast<int>(preconditioner));
  testing::checkBidispersePyramid(settings, 1e-10);
}
