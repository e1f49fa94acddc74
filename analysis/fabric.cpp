#include "analysis/fabric.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace confpack::analysis {

void FabricDef::validate() const {
  if (cosBins < 1) throw std::invalid_argument(fmt::format("fabric: cos_bins must be >= 1 (got {})", cosBins));
  if (azimuthBins < 1)
    throw std::invalid_argument(fmt::format("fabric: azimuth_bins must be >= 1 (got {})", azimuthBins));
}

Fabric fabricOfDirections(const std::vector<core::Vec3>& directions, const std::vector<double>& weights) {
  Fabric f;
  double total = 0.0;
  for (std::size_t k = 0; k < directions.size(); ++k) {
    const double len = directions[k].norm();
    const double w = weights.empty() ? 1.0 : weights[k];
    if (!(len > 0.0) || !(w > 0.0)) continue;
    const core::Vec3 n = directions[k] / len;
    f.tensor += w * n * n.transpose();
    total += w;
    ++f.contacts;
  }
  if (f.contacts == 0) return f;
  f.tensor /= total;
  // Self-adjoint solver: eigenvalues ascending.
  const Eigen::SelfAdjointEigenSolver<core::Mat3> es(f.tensor);
  f.eigenvalues = core::Vec3(es.eigenvalues()(2), es.eigenvalues()(1), es.eigenvalues()(0));
  f.majorAxis = es.eigenvectors().col(2);
  f.anisotropy = 2.5 * (f.eigenvalues(0) - f.eigenvalues(2));
  return f;
}

Fabric fabric(const core::Packing& packing, const BulkRegion& region, const std::vector<CountedContact>& counted,
              const FabricDef& def) {
  def.validate();
  std::vector<core::Vec3> branches;
  std::vector<double> weights;
  std::array<std::vector<core::Vec3>, 3> normals;
  std::array<std::vector<double>, 3> normalWeights;
  for (const CountedContact& c : counted) {
    if (core::isWall(c.b)) continue;
    const double w =
        0.5 * (region.contains(packing.grains[c.a].position.z()) + region.contains(packing.grains[c.b].position.z()));
    if (w == 0.0) continue;
    branches.push_back(c.branch);
    weights.push_back(w);
    normals[static_cast<int>(c.type)].push_back(c.normal);
    normalWeights[static_cast<int>(c.type)].push_back(w);
  }
  Fabric f = fabricOfDirections(branches, weights);
  auto histogram = [&](const std::vector<core::Vec3>& ns, const std::vector<double>& ws, OrientationHistogram& h) {
    h.cosTheta.assign(def.cosBins, 0.0);
    h.azimuth.assign(def.azimuthBins, 0.0);
    double total = 0.0;
    for (std::size_t m = 0; m < ns.size(); ++m) {
      const core::Vec3 n = ns[m].normalized();
      const double w = ws[m];
      const int kc = std::min(def.cosBins - 1, static_cast<int>(std::abs(n.z()) * def.cosBins));
      double phi = std::atan2(n.y(), n.x());
      if (phi < 0.0) phi += std::numbers::pi;
      if (phi >= std::numbers::pi) phi -= std::numbers::pi;
      const int ka = std::min(def.azimuthBins - 1, static_cast<int>(phi / std::numbers::pi * def.azimuthBins));
      h.cosTheta[kc] += w;
      h.azimuth[ka] += w;
      total += w;
      ++h.count;
    }
    if (h.count == 0) return;
    for (double& v : h.cosTheta) v *= static_cast<double>(def.cosBins) / total;
    for (double& v : h.azimuth) v *= static_cast<double>(def.azimuthBins) / total;
  };
  std::vector<core::Vec3> all;
  std::vector<double> allWeights;
  for (int t = 0; t < 3; ++t) {
    histogram(normals[t], normalWeights[t], f.orientation[t]);
    all.insert(all.end(), normals[t].begin(), normals[t].end());
    allWeights.insert(allWeights.end(), normalWeights[t].begin(), normalWeights[t].end());
  }
  histogram(all, allWeights, f.orientation[3]);
  return f;
}

}  // namespace confpack::analysis
