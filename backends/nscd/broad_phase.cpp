#include "backends/nscd/broad_phase.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "core/parallel_failure.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace confpack::nscd {

using core::Vec3;

BroadPhase::BroadPhase(const core::BoxDef& box, double maxReach, int threads)
    : box_(box), threads_(std::max(1, threads)), choice_(threads) {
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

namespace {

int wrapIndex(int i, int m) { return ((i % m) + m) % m; }

// Neighbour cell indices of c along one axis, without duplicates when the grid has < 3 cells.
int neighbours(int c, int m, bool periodic, int* outIdx) {
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
}

// First grain of chunk t of n grains split into `team` contiguous chunks.
int chunkBegin(int n, int t, int team) { return static_cast<int>(static_cast<long long>(n) * t / team); }

}  // namespace

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
  nz_ = std::min(maxLayers, static_cast<int>((zMax - zMin) / hz) + 1);
  const int nCells = nx_ * ny_ * nz_;

  cellOf_.resize(n);
  for (int i = 0; i < n; ++i) {
    const Vec3& p = positions[i];
    const int ix = wrapIndex(static_cast<int>(std::floor(p.x() / hx)), nx_);
    const int iyRaw = static_cast<int>(std::floor(p.y() / hy));
    const int iy = box_.periodicY ? wrapIndex(iyRaw, ny_) : std::clamp(iyRaw, 0, ny_ - 1);
    const int iz = std::clamp(static_cast<int>((p.z() - zMin) / hz), 0, nz_ - 1);
    cellOf_[i] = (iz * ny_ + iy) * nx_ + ix;
  }
  // Counting sort of the grains by cell: cellItems_[cellStart_[c] .. cellStart_[c+1]) are in c.
  cellStart_.assign(nCells + 1, 0);
  for (int i = 0; i < n; ++i) ++cellStart_[cellOf_[i] + 1];
  for (int c = 0; c < nCells; ++c) cellStart_[c + 1] += cellStart_[c];
  cellItems_.resize(n);
  cursor_.assign(cellStart_.begin(), cellStart_.end() - 1);
  for (int i = 0; i < n; ++i) cellItems_[cursor_[cellOf_[i]]++] = i;
  // Grains in ascending order within each cell (the counting sort is stable), and their
  // positions and reaches copied in cell order so that the search reads them contiguously.
  // Neighbour cells along each axis, once per step: nb*_[3 c .. 3 c + count*_[c]).
  auto neighbourTable = [](int m, bool periodic, std::vector<int>& table, std::vector<int>& count) {
    table.resize(3 * static_cast<std::size_t>(m));
    count.resize(m);
    for (int c = 0; c < m; ++c) count[c] = neighbours(c, m, periodic, &table[3 * static_cast<std::size_t>(c)]);
  };
  neighbourTable(nx_, true, nbx_, countX_);
  neighbourTable(ny_, box_.periodicY, nby_, countY_);
  neighbourTable(nz_, false, nbz_, countZ_);
  cellPositions_.resize(n);
  cellReach_.resize(n);
  for (int s = 0; s < n; ++s) {
    cellPositions_[s] = positions[cellItems_[s]];
    cellReach_[s] = reach[cellItems_[s]];
  }

  // The search is ~all of the broad phase's time. Each thread takes a contiguous range of first
  // grains and its output is sorted by (a, b), so the ranges concatenated in order are exactly
  // the single-thread output. Thread 0 writes `out` directly; the others their own buffer.
  const int useful = std::min(threads_, std::max(1, n / kMinGrainsPerThread));
#ifdef _OPENMP
  if (useful > 1) {
    const auto start = std::chrono::steady_clock::now();
    const int wanted = choice_.next() > 1 ? useful : 1;
    if (static_cast<int>(threadPairs_.size()) < wanted) threadPairs_.resize(wanted);
    for (auto& buffer : threadPairs_) buffer.clear();  // a smaller team leaves some unused
    // A pair list that cannot grow throws std::bad_alloc in a thread: rethrown after the region.
    core::ParallelFailure failure;
#pragma omp parallel num_threads(wanted) if (wanted > 1)
    {
      const int t = omp_get_thread_num(), team = omp_get_num_threads();
      failure.capture([&] {
        searchRange(chunkBegin(n, t, team), chunkBegin(n, t + 1, team), positions, reach,
                    t == 0 ? out : threadPairs_[t]);
      });
    }
    failure.rethrow();
    for (std::size_t t = 1; t < threadPairs_.size(); ++t)
      out.insert(out.end(), threadPairs_[t].begin(), threadPairs_[t].end());
    choice_.record(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return;
  }
#endif
  searchRange(0, n, positions, reach, out);
}

void BroadPhase::searchRange(int begin, int end, const std::vector<Vec3>& positions, const std::vector<double>& reach,
                             std::vector<CandidatePair>& out) const {
  const std::vector<int>& start = cellStart_;
  const double halfX = 0.5 * box_.lengthX, halfY = 0.5 * box_.width;
  for (int i = begin; i < end; ++i) {
    const Vec3& p = positions[i];
    // The cell computed in findPairs, decoded (cell = (iz ny + iy) nx + ix).
    const int ix = cellOf_[i] % nx_;
    const int iy = (cellOf_[i] / nx_) % ny_;
    const int iz = cellOf_[i] / (nx_ * ny_);
    const int kx = countX_[ix], ky = countY_[iy], kz = countZ_[iz];
    const int* nbx = &nbx_[3 * static_cast<std::size_t>(ix)];
    const int* nby = &nby_[3 * static_cast<std::size_t>(iy)];
    const int* nbz = &nbz_[3 * static_cast<std::size_t>(iz)];
    const std::size_t first = out.size();
    for (int a = 0; a < kz; ++a)
      for (int b = 0; b < ky; ++b)
        for (int c = 0; c < kx; ++c) {
          const int cell = (nbz[a] * ny_ + nby[b]) * nx_ + nbx[c];
          // Only j > i: a cell's grains are ascending, so walk it down from the top and stop at i.
          for (int s = start[cell + 1] - 1; s >= start[cell] && cellItems_[s] > i; --s) {
            const int j = cellItems_[s];
            const double r = reach[i] + cellReach_[s];
            const Vec3 raw = cellPositions_[s] - p;
            // No early rejection along z: that branch went either way about half the time and
            // the mispredictions cost more than the arithmetic it saved (measured 10-20% slower).
            // box_.minimumImage(raw), skipping nearbyint where it is exactly 0 (|x| < L/2 gives
            // x / L rounded within [-1/2, 1/2], which rounds to 0): same bits, less time.
            Vec3 d = raw;
            if (!(std::abs(d.x()) < halfX)) d.x() -= box_.lengthX * std::nearbyint(d.x() / box_.lengthX);
            if (box_.periodicY && !(std::abs(d.y()) < halfY)) d.y() -= box_.width * std::nearbyint(d.y() / box_.width);
            if (d.squaredNorm() >= r * r) continue;
            CandidatePair pair;
            pair.a = i;
            pair.b = j;
            pair.shiftX = static_cast<std::int8_t>(std::lround((d.x() - raw.x()) / box_.lengthX));
            pair.shiftY = box_.periodicY ? static_cast<std::int8_t>(std::lround((d.y() - raw.y()) / box_.width)) : 0;
            out.push_back(pair);
          }
        }
    // Deterministic order independent of the cell layout: by (a, b). The pairs of one a are
    // contiguous and a increases, so sorting each a's few pairs by b sorts the whole list
    // (insertion sort: a handful of pairs, where std::sort's set-up dominates).
    for (std::size_t k = first + 1; k < out.size(); ++k) {
      const CandidatePair x = out[k];
      std::size_t m = k;
      for (; m > first && out[m - 1].b > x.b; --m) out[m] = out[m - 1];
      out[m] = x;
    }
  }
}

}  // namespace confpack::nscd
