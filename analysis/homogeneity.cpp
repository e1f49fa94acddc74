#include "analysis/homogeneity.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace confpack::analysis {

void HomogeneityDef::validate() const {
  if (!(layer > 0.0) || !std::isfinite(layer))
    throw std::invalid_argument(fmt::format("homogeneity: layer must be positive (got {})", layer));
  if (!(sizeThreshold > 0.0) || !std::isfinite(sizeThreshold))
    throw std::invalid_argument(fmt::format("homogeneity: size_threshold must be positive (got {})", sizeThreshold));
}

namespace {
LayerFractions layers(int count, double layer) {
  LayerFractions f;
  f.large.assign(count, 0);
  f.small.assign(count, 0);
  for (int k = 0; k < count; ++k) f.position.push_back((k + 0.5) * layer);
  return f;
}
void finish(LayerFractions& f) {
  for (std::size_t k = 0; k < f.large.size(); ++k) {
    const int total = f.large[k] + f.small[k];
    f.pLarge.push_back(total > 0 ? double(f.large[k]) / total : 0.0);
    f.pSmall.push_back(total > 0 ? double(f.small[k]) / total : 0.0);
  }
}
}  // namespace

Homogeneity homogeneity(const core::Packing& packing, const BulkRegion& region, const HomogeneityDef& def) {
  def.validate();
  Homogeneity h;
  double zMax = 0.0;
  for (const core::Grain& g : packing.grains) zMax = std::max(zMax, g.position.z());
  const int nz = std::max(1, static_cast<int>(std::floor(zMax / def.layer)) + 1);
  const int ny = std::max(1, static_cast<int>(std::ceil(packing.box.width / def.layer - 1e-9)));
  h.alongZ = layers(nz, def.layer);
  h.alongY = layers(ny, def.layer);
  for (const core::Grain& g : packing.grains) {
    const bool large = g.size > def.sizeThreshold;
    const int kz = std::clamp(static_cast<int>(std::floor(g.position.z() / def.layer)), 0, nz - 1);
    ++(large ? h.alongZ.large : h.alongZ.small)[kz];
    if (!region.contains(g.position.z())) continue;
    const double y = packing.box.wrap(g.position).y();
    const int ky = std::clamp(static_cast<int>(std::floor(y / def.layer)), 0, ny - 1);
    ++(large ? h.alongY.large : h.alongY.small)[ky];
  }
  finish(h.alongZ);
  finish(h.alongY);
  return h;
}

}  // namespace confpack::analysis
