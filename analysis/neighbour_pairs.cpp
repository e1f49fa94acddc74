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
  // Cell counts in double: a box (or a pile) far larger than its grains, say 1e16 d wide, must
  // neither overflow an int nor allocate a grid of that size (a 1e5 x 1e5 box of 170 grains took
  // 2 GB). A real pile has a few grains per cell; past kMaxCellsPerGrain cells per grain the axis
  // with the most cells is coarsened, which finds the same pairs among more candidates. Fewer than
  // 3 cells along a periodic axis would make a cell its own neighbour twice: use one.
  constexpr double kMaxCellsPerGrain = 64.0;
  auto periodicCount = [](double c) { return c >= 3.0 ? c : 1.0; };
  double fx = periodicCount(std::floor(box.lengthX / cell));
  double fy = box.periodicY ? periodicCount(std::floor(box.width / cell)) : std::max(1.0, std::floor(box.width / cell));
  const double fz0 = std::max(1.0, std::floor((zMax - zMin) / cell) + 1.0);
  double fz = fz0;
  while (fx * fy * fz > kMaxCellsPerGrain * n + 1024.0) {
    if (fx >= fy && fx >= fz)
      fx = periodicCount(std::floor(fx / 2.0));
    else if (fy >= fz)
      fy = box.periodicY ? periodicCount(std::floor(fy / 2.0)) : std::max(1.0, std::floor(fy / 2.0));
    else
      fz = std::max(1.0, std::floor(fz / 2.0));
  }
  const int nx = static_cast<int>(fx), ny = static_cast<int>(fy), nz = static_cast<int>(fz);
  const double cx = box.lengthX / nx, cy = box.width / ny;
  // Along z the cells keep the side `cell` unless coarsened (then the grains' extent over nz).
  const double cz = fz == fz0 ? cell : cell * std::ceil(fz0 / fz);

  auto cellOf = [&](const core::Vec3& x) {
    const core::Vec3 p = box.wrap(x);
    const int ix = static_cast<int>(std::clamp(std::floor(p.x() / cx), 0.0, fx - 1.0));
    const int iy = static_cast<int>(std::clamp(std::floor(p.y() / cy), 0.0, fy - 1.0));
    const int iz = static_cast<int>(std::clamp(std::floor((p.z() - zMin) / cz), 0.0, fz - 1.0));
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
