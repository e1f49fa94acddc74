#include "analysis/solid_fraction.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "analysis/cell_count.hpp"
#include "analysis/grain_volumes.hpp"
#include "core/interrupt.hpp"

namespace confpack::analysis {

SolidFraction solidFraction(const core::Packing& packing, const BulkRegion& region) {
  SolidFraction s;
  s.regionVolume = region.volume(packing.box);
  if (!(s.regionVolume > 0.0)) return s;
  for (const core::Grain& g : packing.grains) {
    const double r = g.boundingRadius();
    if (g.position.z() + r <= region.zLow || g.position.z() - r >= region.zHigh) continue;
    s.grainVolume += grainSlabVolume(g, 2, region.zLow, region.zHigh);
  }
  s.phi = s.grainVolume / s.regionVolume;
  return s;
}

void ProfileDef::validate() const {
  if (!(slice > 0.0) || !std::isfinite(slice))
    throw std::invalid_argument(fmt::format("profile: slice thickness must be positive (got {})", slice));
}

std::vector<double> sliceEdges(double width, double slice, std::string_view what) {
  const int n = cellsAlong(width, slice, what);
  std::vector<double> edges(n + 1);
  for (int k = 0; k <= n; ++k) edges[k] = width * k / n;
  return edges;
}

std::vector<double> foldProfile(const std::vector<double>& raw) {
  const std::size_t n = raw.size();
  std::vector<double> out((n + 1) / 2);
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = 0.5 * (raw[k] + raw[n - 1 - k]);
  return out;
}

SolidFractionProfile solidFractionProfile(const core::Packing& packing, const BulkRegion& region,
                                          const ProfileDef& def) {
  def.validate();
  SolidFractionProfile prof;
  const core::BoxDef& box = packing.box;
  const std::vector<double> edges = sliceEdges(box.width, def.slice, "profile: slice");
  const std::size_t n = edges.size() - 1;
  prof.slice = edges[1] - edges[0];
  std::vector<double> volume(n, 0.0);
  for (std::size_t i = 0; i < packing.grains.size(); ++i) {
    // Each grain runs over every slice: with thin slices one grain is a long step.
    core::stopIfRequested([&] {
      return fmt::format("while computing the phi(y) profile (grain {} of {})", i + 1, packing.grains.size());
    });
    const core::Grain& g = packing.grains[i];
    if (!region.contains(g.position.z())) continue;
    const std::vector<double> v = grainSlabVolumes(g, 1, edges, box.periodicY ? box.width : 0.0);
    for (std::size_t k = 0; k < n; ++k) volume[k] += v[k];
  }
  const double sliceVolume = box.lengthX * prof.slice * region.height();
  for (double& v : volume) v = sliceVolume > 0.0 ? v / sliceVolume : 0.0;
  prof.folded = def.fold && !box.periodicY;
  prof.phi = prof.folded ? foldProfile(volume) : volume;
  prof.y.resize(prof.phi.size());
  for (std::size_t k = 0; k < prof.y.size(); ++k) prof.y[k] = 0.5 * (edges[k] + edges[k + 1]);
  return prof;
}

}  // namespace confpack::analysis
