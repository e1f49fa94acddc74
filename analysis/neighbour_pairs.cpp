#include "analysis/neighbour_pairs.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace confpack::analysis {

std::vector<NeighbourPair> neighbourPairs(const core::Packing& packing, double extra) {
  std::vector<NeighbourPair> out;
  const auto& grains = packing.grains;
  const int n = static_cast<int>(grains.size());
  if (n < 2) return out;
  const core::BoxDef& box = packing.box;
  std::vector<double> radius(n);
  double maxR = 0.0, zMin = grains[0].position.z(), zMax = zMin;
  for (int i = 0; i < n; ++i) {
    radius[i] = grains[i].boundingRadius();
    maxR = std::max(maxR, radius[i]);
    zMin = std::min(zMin, grains[i].position.z());
    zMax = std::max(zMax, grains[i].position.z());
  }
  const double cell = 2.0 * maxR + std::max(0.0, extra);
  // Fewer than 3 cells along a periodic axis would make a cell its own neighbour twice: use one.
  auto periodicCount = [&](double len) {
    const int c = static_cast<int>(std::floor(len / cell));
    return c >= 3 ? c : 1;
  };
  const int nx = periodicCount(box.lengthX);
  const int ny = box.periodicY ? periodicCount(box.width) : std::max(1, static_cast<int>(std::floor(box.width / cell)));
  const int nz = std::max(1, static_cast<int>(std::floor((zMax - zMin) / cell)) + 1);
  const double cx = box.lengthX / nx, cy = box.width / ny;

  auto cellOf = [&](const core::Vec3& x) {
    const core::Vec3 p = box.wrap(x);
    const int ix = std::clamp(static_cast<int>(std::floor(p.x() / cx)), 0, nx - 1);
    const int iy = std::clamp(static_cast<int>(std::floor(p.y() / cy)), 0, ny - 1);
    const int iz = std::clamp(static_cast<int>(std::floor((p.z() - zMin) / cell)), 0, nz - 1);
    return std::array<int, 3>{ix, iy, iz};
  };
  const std::size_t cellCount = static_cast<std::size_t>(nx) * ny * nz;
  auto flat = [&](int ix, int iy, int iz) { return (static_cast<std::size_t>(iz) * ny + iy) * nx + ix; };
  // Counting sort of grains into cells (CSR layout: flat arrays, no per-cell vectors).
  std::vector<int> start(cellCount + 1, 0), cellOfGrain(n), order(n);
  for (int i = 0; i < n; ++i) {
    const auto c = cellOf(grains[i].position);
    cellOfGrain[i] = static_cast<int>(flat(c[0], c[1], c[2]));
    ++start[cellOfGrain[i] + 1];
  }
  for (std::size_t c = 0; c < cellCount; ++c) start[c + 1] += start[c];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int i = 0; i < n; ++i) order[fill[cellOfGrain[i]]++] = i;
  }

  std::vector<std::size_t> neighbours;
  for (int i = 0; i < n; ++i) {
    const auto c = cellOf(grains[i].position);
    neighbours.clear();
    for (int dz = -1; dz <= 1; ++dz) {
      const int iz = c[2] + dz;
      if (iz < 0 || iz >= nz) continue;
      for (int dy = -1; dy <= 1; ++dy) {
        int iy = c[1] + dy;
        if (box.periodicY)
          iy = (iy + ny) % ny;
        else if (iy < 0 || iy >= ny)
          continue;
        for (int dx = -1; dx <= 1; ++dx) {
          const int ix = (c[0] + dx + nx) % nx;
          neighbours.push_back(flat(ix, iy, iz));
        }
      }
    }
    std::sort(neighbours.begin(), neighbours.end());
    neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
    for (std::size_t nc : neighbours)
      for (int k = start[nc]; k < start[nc + 1]; ++k) {
        const int j = order[k];
        if (j <= i) continue;
        const core::Vec3 sep = box.minimumImage(grains[j].position - grains[i].position);
        const double reach = radius[i] + radius[j] + extra;
        if (sep.squaredNorm() <= reach * reach) out.push_back({i, j, sep});
      }
  }
  std::sort(out.begin(), out.end(),
            [](const NeighbourPair& a, const NeighbourPair& b) { return a.i != b.i ? a.i < b.i : a.j < b.j; });
  return out;
}

}  // namespace confpack::analysis
