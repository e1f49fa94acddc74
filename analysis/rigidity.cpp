#include "analysis/rigidity.hpp"

#include <fmt/format.h>

#include <Eigen/SPQRSupport>
#include <Eigen/SparseCore>
#include <algorithm>

#include "core/blas_lock.hpp"

namespace confpack::analysis {

std::optional<Rigidity> sphereRigidity(const core::Packing& packing, const std::vector<CountedContact>& counted,
                                       std::string* whyNot) {
  const auto fail = [&](std::string why) -> std::optional<Rigidity> {
    if (whyNot) *whyNot = std::move(why);
    return std::nullopt;
  };
  const int n = static_cast<int>(packing.grains.size());
  if (std::any_of(packing.grains.begin(), packing.grains.end(),
                  [](const core::Grain& g) { return g.shape != core::ShapeKind::Sphere; }))
    return fail("defined for sphere packings only");
  if (packing.walls.friction > 0.0) return fail("defined between frictionless walls only");
  if (n > kRigidityMaxGrains) return fail(fmt::format("more than {} grains", kRigidityMaxGrains));

  Rigidity r;
  r.contacts = static_cast<int>(counted.size());
  r.degreesOfFreedom = 3 * n;
  if (counted.empty() || n == 0) {
    r.mechanisms = r.degreesOfFreedom;
    return r;
  }
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(counted.size() * 6);
  for (std::size_t c = 0; c < counted.size(); ++c) {
    const CountedContact& k = counted[c];
    const int row = static_cast<int>(c);
    for (int d = 0; d < 3; ++d) {
      entries.emplace_back(row, 3 * k.a + d, -k.normal[d]);
      if (!core::isWall(k.b)) entries.emplace_back(row, 3 * k.b + d, k.normal[d]);
    }
  }
  Eigen::SparseMatrix<double> g(r.contacts, r.degreesOfFreedom);
  g.setFromTriplets(entries.begin(), entries.end());
  g.makeCompressed();
  // SuiteSparseQR: a multifrontal rank-revealing QR (its default tolerance, 20 (m + 3N) eps times
  // the largest column norm); Eigen's own SparseQR took 28 s on a 1,968-sphere packing where this
  // takes 0.08 s. It calls LAPACK and BLAS, hence the lock.
  Eigen::SPQR<Eigen::SparseMatrix<double>> qr;
  {
    const auto lock = core::blasLock();
    qr.compute(g);
  }
  if (qr.info() != Eigen::Success) return fail("the QR factorisation failed");
  r.rank = static_cast<int>(qr.rank());
  r.selfStresses = r.contacts - r.rank;
  r.mechanisms = r.degreesOfFreedom - r.rank;
  return r;
}

}  // namespace confpack::analysis
