#include "backends/nscd/broad_phase.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace confpack::nscd {

using core::Vec3;

BroadPhase::BroadPhase(const core::BoxDef& box, double maxReach) : box_(box) {
  if (!(maxReach > 0.0)) throw std::invalid_argument("nscd broad phase: grain reach must be positive");
  cell_ = 2.0 * maxReach;
  // The minimum-image convention is exact only if no grain can touch two images of another one.
  if (box.lengthX < 2.0 * cell_)
    throw std::invalid_argument(fmt::format(
        "nscd: box length_x {} is too short for grains of interaction diameter {} (need >= {})", box.lengthX,
        cell_, 2.0 * cell_));
  if (box.periodicY && box.width < 2.0 * cell_)
    throw std::invalid_argument(fmt::format(
        "nscd: periodic width {} is too short for grains of interaction diameter {} (need >= {})", box.width,
        cell_, 2.0 * cell_));
  nx_ = std::max(1, static_cast<int>(std::floor(box.lengthX / cell_)));
  ny_ = std::max(1, static_cast<int>(std::floor(box.width / cell_)));
}

void BroadPhase::findPairs(const std::vector<Vec3>& positions, const std::vector<double>& reach,
                           std::vector<CandidatePair>& out) {
  out.clear();
  const int n = static_cast<int>(positions.size());
  if (n == 0) return;
  // Periodic directions use cells of size L/n >= cell_; the z direction spans the pile. If a grain
  // flew far away, the z cells are enlarged so that the grid stays small (at most ~2n layers).
  const double hx = box_.lengthX / nx_, hy = box_.width / ny_;
  double zMin = positions[0].z(), zMax = zMin;
  for (const Vec3& p : positions) {
    zMin = std::min(zMin, p.z());
    zMax = std::max(zMax, p.z());
  }
  const int maxLayers = 2 * n + 1;
  double hz = std::max(cell_, (zMax - zMin) / maxLayers);
  const int nz = std::min(maxLayers, static_cast<int>((zMax - zMin) / hz) + 1);
  const int nCells = nx_ * ny_ * nz;

  auto wrapIndex = [](int i, int m) { return ((i % m) + m) % m; };
  cellOf_.resize(n);
  for (int i = 0; i < n; ++i) {
    const Vec3& p = positions[i];
    const int ix = wrapIndex(static_cast<int>(std::floor(p.x() / hx)), nx_);
    const int iyRaw = static_cast<int>(std::floor(p.y() / hy));
    const int iy = box_.periodicY ? wrapIndex(iyRaw, ny_) : std::clamp(iyRaw, 0, ny_ - 1);
    const int iz = std::clamp(static_cast<int>((p.z() - zMin) / hz), 0, nz - 1);
    cellOf_[i] = (iz * ny_ + iy) * nx_ + ix;
  }
  // Counting sort of the grains by cell: cellItems_[cellStart_[c] .. cellStart_[c+1]) are in c.
  cellStart_.assign(nCells + 1, 0);
  for (int i = 0; i < n; ++i) ++cellStart_[cellOf_[i] + 1];
  for (int c = 0; c < nCells; ++c) cellStart_[c + 1] += cellStart_[c];
  cellItems_.resize(n);
  cursor_.assign(cellStart_.begin(), cellStart_.end() - 1);
  for (int i = 0; i < n; ++i) cellItems_[cursor_[cellOf_[i]]++] = i;
  const std::vector<int>& start = cellStart_;

  // The pair test does not depend on the visiting order; the output is sorted at the end so that
  // the contact order (hence the Gauss-Seidel order) is a function of the configuration only.
  int nbx[3], nby[3], nbz[3];
  for (int i = 0; i < n; ++i) {
    const Vec3& p = positions[i];
    // The cell computed above, decoded (cell = (iz ny + iy) nx + ix).
    const int ix = cellOf_[i] % nx_;
    const int iy = (cellOf_[i] / nx_) % ny_;
    const int iz = cellOf_[i] / (nx_ * ny_);
    // Neighbour cell indices along each axis, without duplicates when the grid has < 3 cells.
    auto neighbours = [&](int c, int m, bool periodic, int* outIdx) {
      int k = 0;
      for (int d = -1; d <= 1; ++d) {
        int j = c + d;
        if (periodic) j = wrapIndex(j, m);
        else if (j < 0 || j >= m) continue;
        bool seen = false;
        for (int q = 0; q < k; ++q) seen |= outIdx[q] == j;
        if (!seen) outIdx[k++] = j;
      }
      return k;
    };
    const int kx = neighbours(ix, nx_, true, nbx);
    const int ky = neighbours(iy, ny_, box_.periodicY, nby);
    const int kz = neighbours(iz, nz, false, nbz);
    for (int a = 0; a < kz; ++a)
      for (int b = 0; b < ky; ++b)
        for (int c = 0; c < kx; ++c) {
          const int cell = (nbz[a] * ny_ + nby[b]) * nx_ + nbx[c];
          for (int s = start[cell]; s < start[cell + 1]; ++s) {
            const int j = cellItems_[s];
            if (j <= i) continue;
            const Vec3 raw = positions[j] - p;
            const Vec3 d = box_.minimumImage(raw);
            const double r = reach[i] + reach[j];
            if (d.squaredNorm() >= r * r) continue;
            CandidatePair pair;
            pair.a = i;
            pair.b = j;
            pair.shiftX = static_cast<std::int8_t>(std::lround((d.x() - raw.x()) / box_.lengthX));
            pair.shiftY = box_.periodicY ? static_cast<std::int8_t>(std::lround((d.y() - raw.y()) / box_.width)) : 0;
            out.push_back(pair);
          }
        }
  }
  // Deterministic order independent of the cell layout: by (a, b).
  std::sort(out.begin(), out.end(), [](const CandidatePair& l, const CandidatePair& r) {
    return l.a != r.a ? l.a < r.a : l.b < r.b;
  });
}

}  // namespace confpack::nscd
