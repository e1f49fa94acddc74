#include "collision/cell_list.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace confpack::collision {

namespace {

void requirePositive(double v, const char* what) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw std::invalid_argument(fmt::format("cell list: {} must be a positive number (got {})", what, v));
}

// Neighbour cells of c along one axis of m cells, each once (with fewer than 3 cells, c - 1 and
// c + 1 are the same cell, or c itself). Returns their count, written to out.
int neighbours(int c, int m, bool periodic, int* out) {
  int k = 0;
  for (int d = -1; d <= 1; ++d) {
    int j = c + d;
    if (periodic)
      j = ((j % m) + m) % m;
    else if (j < 0 || j >= m)
      continue;
    bool seen = false;
    for (int q = 0; q < k; ++q) seen |= out[q] == j;
    if (!seen) out[k++] = j;
  }
  return k;
}

// Cells of side >= cutoff along a length: as many as fit, at least one (counted in double: a
// length of 1e16 cutoffs must not overflow an int; setColumnsAndRows caps the count).
double cellsAlong(double length, double cutoff) {
  return std::max(1.0, std::floor(length / cutoff));
}

}  // namespace

void CellList::AxisNeighbours::build(int m, bool periodic) {
  cells.resize(3 * static_cast<std::size_t>(m));
  count.resize(static_cast<std::size_t>(m));
  for (int c = 0; c < m; ++c)
    count[static_cast<std::size_t>(c)] = neighbours(c, m, periodic, &cells[3 * static_cast<std::size_t>(c)]);
}

CellList::CellList(const BoxDef& box, double cutoff, double zMin) : box_(box), cutoff_(cutoff), zMin_(zMin) {
  requirePositive(cutoff, "cutoff");
  requirePositive(box.lengthX, "box length_x");
  requirePositive(box.width, "box width");
  hz_ = cutoff;
  setColumnsAndRows(cellsAlong(box.lengthX, cutoff), cellsAlong(box.width, cutoff));
}

void CellList::setColumnsAndRows(double nx, double ny) {
  // As many whole cells as fit along each length, so that every cell is at least `cutoff` and
  // the cells tile a period exactly; at most kMaxCellsPerAxis (a box of 1e58 cutoffs).
  nx_ = static_cast<int>(std::min(nx, kMaxCellsPerAxis));
  ny_ = static_cast<int>(std::min(ny, kMaxCellsPerAxis));
  hx_ = box_.lengthX / nx_;
  hy_ = box_.width / ny_;
}

void CellList::clear() {
  std::copy(first_.begin(), first_.end() - 1, end_.begin());
  count_ = 0;
  points_ = {};
}

void CellList::build(std::span<const Vec3> positions) {
  const int n = static_cast<int>(positions.size());
  count_ = positions.size();
  points_ = positions;
  first_.assign(1, 0);
  end_.clear();
  ids_.clear();
  positions_.clear();
  nz_ = 0;
  if (n == 0) return;

  // Layers over the points' z range. If a point flew far away the layers are enlarged so that
  // there are at most 2 n + 1 of them.
  double zMin = positions[0].z(), zMax = zMin;
  for (const Vec3& p : positions) {
    zMin = std::min(zMin, p.z());
    zMax = std::max(zMax, p.z());
  }
  const double extent = zMax - zMin;
  const double maxLayers = 2.0 * n + 1.0;
  double hz = std::max(cutoff_, extent / maxLayers);
  double fx = cellsAlong(box_.lengthX, cutoff_), fy = cellsAlong(box_.width, cutoff_);
  double fz = std::min(maxLayers, std::floor(extent / hz) + 1.0);
  // A real pile has a few points per cell. Past kMaxCellsPerPoint the axis with the most cells
  // is halved, which finds the same pairs among more candidates.
  const double fz0 = fz;
  while (fx * fy * fz > kMaxCellsPerPoint * n + kSpareCells) {
    if (fx >= fy && fx >= fz)
      fx = std::max(1.0, std::floor(fx / 2.0));
    else if (fy >= fz)
      fy = std::max(1.0, std::floor(fy / 2.0));
    else
      fz = std::max(1.0, std::floor(fz / 2.0));
  }
  if (fz < fz0) hz = std::max(hz, extent / fz);
  setColumnsAndRows(fx, fy);
  zMin_ = zMin;
  hz_ = hz;
  nz_ = static_cast<int>(fz);
  const std::size_t cellCount =
      static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_) * static_cast<std::size_t>(nz_);

  cellOf_.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const Vec3& p = positions[static_cast<std::size_t>(i)];
    const int iz = clampIndex(std::floor((p.z() - zMin) / hz), nz_);
    cellOf_[static_cast<std::size_t>(i)] = static_cast<int>(cellIndex(columnOf(p.x()), rowOf(p.y()), iz));
  }
  // Counting sort by cell (stable: ascending ids within a cell), the positions copied in slot
  // order so that the pair search reads them contiguously.
  first_.assign(cellCount + 1, 0);
  for (int c : cellOf_) ++first_[static_cast<std::size_t>(c) + 1];
  for (std::size_t c = 0; c < cellCount; ++c) first_[c + 1] += first_[c];
  end_.assign(first_.begin(), first_.end() - 1);  // the cursor of the sort, then each cell's end
  ids_.resize(static_cast<std::size_t>(n));
  positions_.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const int s = end_[static_cast<std::size_t>(cellOf_[static_cast<std::size_t>(i)])]++;
    ids_[static_cast<std::size_t>(s)] = i;
    positions_[static_cast<std::size_t>(s)] = positions[static_cast<std::size_t>(i)];
  }
  alongX_.build(nx_, true);
  alongY_.build(ny_, box_.periodicY);
  alongZ_.build(nz_, false);
}

void CellList::addLayers(int layers) {
  // Appended at the end (the layer is the slowest index), each cell with kRoom free slots.
  const std::size_t added =
      static_cast<std::size_t>(layers) * static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  int next = first_.back();
  for (std::size_t k = 0; k < added; ++k) {
    end_.push_back(next);
    next += kRoom;
    first_.push_back(next);
  }
  ids_.resize(static_cast<std::size_t>(next));
  positions_.resize(static_cast<std::size_t>(next));
  nz_ += layers;
}

void CellList::relayout() {
  // Every cell gets room for twice its points (at least kRoom), in the same order: the copies
  // stay amortised, as for a growing vector.
  const std::size_t cellCount = end_.size();
  std::size_t total = 0;
  for (std::size_t c = 0; c < cellCount; ++c)
    total += static_cast<std::size_t>(std::max(kRoom, 2 * (end_[c] - first_[c])));
  std::vector<int> ids(total);
  std::vector<Vec3> positions(total);
  int next = 0;
  for (std::size_t c = 0; c < cellCount; ++c) {
    const int n = end_[c] - first_[c];
    std::copy(ids_.begin() + first_[c], ids_.begin() + end_[c], ids.begin() + next);
    std::copy(positions_.begin() + first_[c], positions_.begin() + end_[c], positions.begin() + next);
    first_[c] = next;
    end_[c] = next + n;
    next += std::max(kRoom, 2 * n);
  }
  first_[cellCount] = next;
  ids_.swap(ids);
  positions_.swap(positions);
}

void CellList::insert(int id, const Vec3& position) {
  const Vec3 p = box_.wrap(position);
  const double layer = std::floor((p.z() - zMin_) / hz_);
  const int iz = layer > 0.0 ? static_cast<int>(layer) : 0;
  if (iz >= nz_) addLayers(iz + 1 - nz_);
  const std::size_t c = cellIndex(columnOf(p.x()), rowOf(p.y()), iz);
  if (end_[c] == first_[c + 1]) relayout();
  const int s = end_[c]++;
  ids_[static_cast<std::size_t>(s)] = id;
  positions_[static_cast<std::size_t>(s)] = p;
  ++count_;
}

std::vector<ImageHit> CellList::near(const Vec3& p, double radius) const {
  std::vector<ImageHit> out;
  forEachNear(p, radius, [&](const ImageHit& hit) { out.push_back(hit); });
  return out;
}

}  // namespace confpack::collision
