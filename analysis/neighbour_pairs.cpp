#include "analysis/neighbour_pairs.hpp"

#include <algorithm>

#include "collision/cell_list.hpp"

namespace confpack::analysis {

std::vector<NeighbourPair> neighbourPairs(const core::Packing& packing, double extra) {
  std::vector<NeighbourPair> out;
  const auto& grains = packing.grains;
  const std::size_t n = grains.size();
  if (n < 2) return out;
  std::vector<core::Vec3> positions(n);
  std::vector<double> radius(n);
  double maxR = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    positions[i] = grains[i].position;
    radius[i] = grains[i].boundingRadius();
    maxR = std::max(maxR, radius[i]);
  }
  const core::BoxDef& box = packing.box;
  collision::CellList cells(box, 2.0 * maxR + std::max(0.0, extra));
  cells.build(positions);
  cells.findPairs<&NeighbourPair::j>(
      [&](std::vector<NeighbourPair>& o, int i, int j, int, const core::Vec3&, const core::Vec3& raw) {
        // BoxDef::minimumImage itself, for the bits of a zero component's sign too.
        const core::Vec3 sep = box.minimumImage(raw);
        const double reach = radius[static_cast<std::size_t>(i)] + radius[static_cast<std::size_t>(j)] + extra;
        if (sep.squaredNorm() <= reach * reach) o.push_back({i, j, sep});
      },
      out);
  return out;
}

}  // namespace confpack::analysis
