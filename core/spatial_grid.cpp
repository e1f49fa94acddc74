#include "core/spatial_grid.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace confpack::core {

SpatialGrid::SpatialGrid(const BoxDef& box, double minCellSize, double zMin) : box_(box), zMin_(zMin) {
  if (!(minCellSize > 0.0) || !std::isfinite(minCellSize))
    throw std::invalid_argument(fmt::format("spatial grid: cell size must be positive (got {})", minCellSize));
  box_.validate();
  // As many whole cells as fit along each period, so that every cell is at least minCellSize and
  // the cells tile the period exactly (a query of radius <= cell size then needs 3 cells a side).
  nx_ = std::max(1, static_cast<int>(std::floor(box_.lengthX / minCellSize)));
  ny_ = std::max(1, static_cast<int>(std::floor(box_.width / minCellSize)));
  cellX_ = box_.lengthX / nx_;
  cellY_ = box_.width / ny_;
  cellZ_ = minCellSize;
}

int SpatialGrid::layerOf(double z) const { return std::max(0L, floorIndex(z - zMin_, cellZ_)); }

void SpatialGrid::insert(int id, const Vec3& position) {
  const Vec3 p = box_.wrap(position);
  // Clamp against round-off at the top of a period (wrap can return exactly the period).
  const long ix = std::clamp<long>(floorIndex(p.x(), cellX_), 0, nx_ - 1);
  const long iy = std::clamp<long>(floorIndex(p.y(), cellY_), 0, ny_ - 1);
  const int iz = layerOf(p.z());
  if (iz >= nz_) {
    nz_ = iz + 1;
    cells_.resize(static_cast<std::size_t>(nz_) * static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_));
  }
  cells_[cellIndex(ix, iy, iz)].push_back({id, p});
  ++count_;
}

void SpatialGrid::clear() {
  for (auto& c : cells_) c.clear();
  count_ = 0;
}

}  // namespace confpack::core
