#include "analysis/rigidity.hpp"

#include <fmt/format.h>

#include <Eigen/SPQRSupport>
#include <Eigen/SparseCore>
#include <algorithm>

#include "core/blas_lock.hpp"

namespace confpack::analysis {

namespace {

// The points of a contact that carry its independent constraints: the first point, then the one
// farthest from it in the contact plane, then the one farthest from the line through both; each
// kept only if it lies at least `span` off the span of those before (contact-plane components).
std::vector<core::Vec3> independentPoints(const std::vector<core::Vec3>& points, const core::Vec3& n, double span) {
  const auto inPlane = [&](const core::Vec3& d) -> core::Vec3 { return d - d.dot(n) * n; };
  std::vector<core::Vec3> out = {points.front()};
  const auto farthest = [&](const auto& distance) {
    std::size_t best = 0;
    double far = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (const double d = distance(points[i]); d > far) {
        far = d;
        best = i;
      }
    return std::pair(best, far);
  };
  const auto [second, d1] = farthest([&](const core::Vec3& p) { return inPlane(p - out[0]).norm(); });
  if (d1 < span) return out;
  out.push_back(points[second]);
  const core::Vec3 u = inPlane(out[1] - out[0]).normalized();
  const auto [third, d2] = farthest([&](const core::Vec3& p) {
    const core::Vec3 d = inPlane(p - out[0]);
    return (d - d.dot(u) * u).norm();
  });
  if (d2 >= span) out.push_back(points[third]);
  return out;
}

}  // namespace

std::optional<Rigidity> contactRigidity(const core::Packing& packing, const std::vector<CountedContact>& counted,
                                        std::string* whyNot) {
  const auto fail = [&](std::string why) -> std::optional<Rigidity> {
    if (whyNot) *whyNot = std::move(why);
    return std::nullopt;
  };
  const int n = static_cast<int>(packing.grains.size());
  if (packing.walls.friction > 0.0) return fail("defined between frictionless walls only");
  if (n > kRigidityMaxGrains) return fail(fmt::format("more than {} grains", kRigidityMaxGrains));
  // A packing mixes no shapes (docs/model.md): spheres take 3 columns, pinacoids 6.
  const bool spheres = std::all_of(packing.grains.begin(), packing.grains.end(),
                                   [](const core::Grain& g) { return g.shape == core::ShapeKind::Sphere; });
  const int dof = spheres ? 3 : 6;

  Rigidity r;
  r.contacts = static_cast<int>(counted.size());
  r.degreesOfFreedom = dof * n;
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<char> wallRow;  // per row: a floor or side-wall constraint
  int row = 0;
  const auto addGrain = [&](int grain, double sign, const core::Vec3& normal, const core::Vec3& point) {
    for (int d = 0; d < 3; ++d) entries.emplace_back(row, dof * grain + d, sign * normal[d]);
    if (spheres) return;
    const core::Vec3 lever = packing.box.minimumImage(point - packing.grains[grain].position);
    const core::Vec3 turn = lever.cross(normal);
    for (int d = 0; d < 3; ++d) entries.emplace_back(row, dof * grain + 3 + d, sign * turn[d]);
  };
  for (const CountedContact& c : counted) {
    if (spheres) {
      addGrain(c.a, -1.0, c.normal, core::Vec3::Zero());
      if (!core::isWall(c.b)) addGrain(c.b, 1.0, c.normal, core::Vec3::Zero());
      wallRow.push_back(core::isWall(c.b));
      ++row;
      continue;
    }
    if (c.points.empty()) return fail("a pinacoid contact has no points");
    double size = packing.grains[c.a].size;
    if (!core::isWall(c.b)) size = std::min(size, packing.grains[c.b].size);
    for (const core::Vec3& p : independentPoints(c.points, c.normal, kConstraintSpan * size)) {
      addGrain(c.a, -1.0, c.normal, p);
      if (!core::isWall(c.b)) addGrain(c.b, 1.0, c.normal, p);
      wallRow.push_back(core::isWall(c.b));
      ++row;
    }
  }
  r.constraints = row;
  r.grainConstraints = static_cast<int>(std::count(wallRow.begin(), wallRow.end(), 0));
  if (row == 0) return r;
  // The rank of the rows `keep` selects, or -1 if the factorisation failed. SuiteSparseQR: a
  // multifrontal rank-revealing QR (its default tolerance, 20 (m + n_dof) eps times the largest
  // column norm; on a 1,064-pinacoid pile the singular values of G jump from 5e-16 to 1.9e-3, so
  // any tolerance between gives the same rank). Eigen's own SparseQR took 28 s on a 1,968-sphere
  // packing where this takes 0.08 s. It calls LAPACK and BLAS, hence the lock.
  const auto rankOf = [&](const auto& keep) -> long {
    std::vector<int> newRow(static_cast<std::size_t>(row), -1);
    int rows = 0;
    for (int i = 0; i < row; ++i)
      if (keep(i)) newRow[static_cast<std::size_t>(i)] = rows++;
    if (rows == 0) return 0;
    std::vector<Eigen::Triplet<double>> kept;
    for (const auto& e : entries)
      if (const int i = newRow[static_cast<std::size_t>(e.row())]; i >= 0) kept.emplace_back(i, e.col(), e.value());
    Eigen::SparseMatrix<double> g(rows, r.degreesOfFreedom);
    g.setFromTriplets(kept.begin(), kept.end());
    g.makeCompressed();
    const auto lock = core::blasLock();  // before the factor, which its destructor frees
    Eigen::SPQR<Eigen::SparseMatrix<double>> qr;
    qr.compute(g);
    return qr.info() == Eigen::Success ? static_cast<long>(qr.rank()) : -1;
  };
  const long all = rankOf([](int) { return true; });
  const long betweenGrains = rankOf([&](int i) { return !wallRow[static_cast<std::size_t>(i)]; });
  if (all < 0 || betweenGrains < 0) return fail("the QR factorisation failed");
  r.rank = static_cast<int>(all);
  r.grainRank = static_cast<int>(betweenGrains);
  return r;
}

}  // namespace confpack::analysis
