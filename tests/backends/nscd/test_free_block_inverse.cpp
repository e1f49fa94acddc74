// The "cholesky" preconditioner's factor (backends/nscd/free_block_inverse.hpp): its products are
// (A_FF + eps I)^-1 phi for A = G M^-1 G^T, whether the factor was made afresh or updated and
// downdated for a changed free set.
#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <random>
#include <vector>

#include "backends/nscd/free_block_inverse.hpp"

using namespace confpack;
using core::Vec3;

namespace {

struct RandomRows {
  std::vector<nscd::JacobianRow> rows;
  std::vector<nscd::BodyInverseMass> bodies;
  bool angular = false;

  RandomRows(int bodyCount, int rowCount, bool withAngular, unsigned seed)
      : bodies(bodyCount + 1), angular(withAngular) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0), mass(0.5, 2.0);
    std::uniform_int_distribution<int> body(0, bodyCount - 1);
    for (int b = 0; b < bodyCount; ++b) {
      bodies[b].invMass = 1.0 / mass(rng);
      const Eigen::Matrix3d r = Eigen::Matrix3d::NullaryExpr([&] { return u(rng); });
      bodies[b].invInertia = (r * r.transpose() + Eigen::Matrix3d::Identity()).inverse();
    }
    // The last body is the world: it never moves (zero inverse mass).
    const auto vec = [&] { return Vec3(u(rng), u(rng), u(rng)); };
    for (int k = 0; k < rowCount; ++k) {
      nscd::JacobianRow row;
      row.n = vec().normalized();
      row.a = body(rng);
      row.b = k % 7 == 0 ? bodyCount : body(rng);
      if (row.b == row.a) row.b = (row.a + 1) % bodyCount;
      if (angular) {
        row.axn = vec();
        row.bxn = row.b == bodyCount ? Vec3::Zero() : vec();
      } else {
        row.axn = row.bxn = Vec3::Zero();
      }
      rows.push_back(row);
    }
  }

  // A = G M^-1 G^T, densely.
  Eigen::MatrixXd operatorA() const {
    const int world = static_cast<int>(bodies.size()) - 1;
    const int dof = 6;
    Eigen::MatrixXd g = Eigen::MatrixXd::Zero(static_cast<int>(rows.size()), dof * world);
    Eigen::MatrixXd minv = Eigen::MatrixXd::Zero(dof * world, dof * world);
    for (int b = 0; b < world; ++b) {
      minv.block<3, 3>(dof * b, dof * b) = bodies[b].invMass * Eigen::Matrix3d::Identity();
      minv.block<3, 3>(dof * b + 3, dof * b + 3) = bodies[b].invInertia;
    }
    for (int k = 0; k < static_cast<int>(rows.size()); ++k) {
      const nscd::JacobianRow& row = rows[k];
      g.block<1, 3>(k, dof * row.a) = -row.n.transpose();
      g.block<1, 3>(k, dof * row.a + 3) = -row.axn.transpose();
      if (row.b != world) {
        g.block<1, 3>(k, dof * row.b) = row.n.transpose();
        g.block<1, 3>(k, dof * row.b + 3) = row.bxn.transpose();
      }
    }
    return g * minv * g.transpose();
  }
};

// Largest |z - (A_FF + eps I)^-1 g_F| over F, relative to the largest |z|; and whether z is 0 off F.
std::pair<double, bool> compare(const Eigen::MatrixXd& a, const std::vector<double>& y, const std::vector<double>& g,
                                const std::vector<double>& z, double eps) {
  std::vector<int> free;
  for (int k = 0; k < static_cast<int>(y.size()); ++k)
    if (y[k] > 0.0) free.push_back(k);
  const int f = static_cast<int>(free.size());
  Eigen::MatrixXd aff(f, f);
  Eigen::VectorXd gf(f);
  for (int i = 0; i < f; ++i) {
    gf[i] = g[free[i]];
    for (int j = 0; j < f; ++j) aff(i, j) = a(free[i], free[j]);
  }
  const Eigen::VectorXd expected = (aff + eps * Eigen::MatrixXd::Identity(f, f)).ldlt().solve(gf);
  double difference = 0.0;
  for (int i = 0; i < f; ++i) difference = std::max(difference, std::abs(z[free[i]] - expected[i]));
  bool zeroOff = true;
  for (int k = 0; k < static_cast<int>(y.size()); ++k) zeroOff = zeroOff && (y[k] > 0.0 || z[k] == 0.0);
  return {difference / expected.cwiseAbs().maxCoeff(), zeroOff};
}

}  // namespace

TEST_CASE("nscd free block inverse: (A_FF + eps I)^-1 g, factored afresh, updated and downdated", "[nscd]") {
  const bool angular = GENERATE(false, true);
  const double eps = GENERATE(1e-5, 1e-2);
  const RandomRows problem(40, 150, angular, angular ? 3u : 4u);
  const Eigen::MatrixXd a = problem.operatorA();
  const int m = static_cast<int>(problem.rows.size());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> y(m), g(m), z(m);
  for (int k = 0; k < m; ++k) {
    y[k] = k % 3 == 0 ? 0.0 : 1.0;
    g[k] = u(rng);
  }
  nscd::FreeBlockInverse inverse;
  inverse.build(problem.rows, problem.bodies, angular, eps);
  INFO("angular " << angular << ", eps " << eps);
  REQUIRE(inverse.factor(y));
  inverse.apply(g, z);
  auto [difference, zeroOff] = compare(a, y, g, z, eps);
  CHECK(difference < 1e-8);
  CHECK(zeroOff);
  CHECK(inverse.factorisations() == 1);
  // A few rows change: the factor is updated (rows freed) and downdated (rows bound).
  for (int k : {0, 3, 6}) y[k] = 1.0;
  for (int k : {1, 2, 4}) y[k] = 0.0;
  REQUIRE(inverse.factor(y));
  inverse.apply(g, z);
  std::tie(difference, zeroOff) = compare(a, y, g, z, eps);
  CHECK(difference < 1e-8);
  CHECK(zeroOff);
  CHECK(inverse.factorisations() == 1);
  CHECK(inverse.updates() == 1);
  // The same free set again: nothing to redo.
  REQUIRE(inverse.factor(y));
  CHECK(inverse.updates() == 1);
}

TEST_CASE("nscd free block inverse: a free set changed by more than kRefactorRows rows is factored afresh", "[nscd]") {
  const RandomRows problem(200, 2 * static_cast<int>(nscd::FreeBlockInverse::kRefactorRows) + 100, false, 7u);
  const Eigen::MatrixXd a = problem.operatorA();
  const int m = static_cast<int>(problem.rows.size());
  std::vector<double> y(m, 1.0), g(m), z(m);
  for (int k = 0; k < m; ++k) g[k] = std::sin(k + 1.0);
  nscd::FreeBlockInverse inverse;
  inverse.build(problem.rows, problem.bodies, false, 1e-4);
  REQUIRE(inverse.factor(y));
  for (int k = 0; k < m; k += 2) y[k] = 0.0;  // half the rows bound: over kRefactorRows
  REQUIRE(inverse.factor(y));
  CHECK(inverse.factorisations() == 2);
  CHECK(inverse.updates() == 0);
  inverse.apply(g, z);
  const auto [difference, zeroOff] = compare(a, y, g, z, 1e-4);
  CHECK(difference < 1e-8);
  CHECK(zeroOff);
}
