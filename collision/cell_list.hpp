#pragma once
// The periodic cell list (docs/model.md, "Box"): the one neighbour search of the code base, used
// by the deposition's placement queries, the nscd broad phase, Bullet's pairs across periodic
// faces and the analysis' neighbour pairs.
//
// Cells. Along x (periodic, period L_x) and y (periodic with period W, or [0, W] between the side
// walls) the box is cut into floor(length / cutoff) cells of side length / count >= cutoff; along
// z (floor below, open above) layers of side >= cutoff start at zMin. Two points within `cutoff`
// of each other, for some periodic image, are therefore in the same or in neighbouring cells. A
// point counts in the cell of its wrapped coordinates; outside [0, W] between walls, or below zMin,
// in the edge cell.
//
// Filling. build() bins a whole set of points at once by a counting sort: layers fitted to the
// points' z range, and the grid coarsened if it would have more than kMaxCellsPerPoint cells per
// point (a box, or a pile, far larger than its grains). insert() adds one point at a time, wrapped
// into the box, and adds layers upwards as points arrive (the deposition's growing pile). Either
// way each cell's points are contiguous in flat arrays ("slots"), in the order they arrived:
// ascending ids after build().
//
// Queries, and the order they report in (results depend on it, so it is part of the contract):
// - findPairs (after build()): every pair i < j of points in the same or in neighbouring cells,
//   each once, with its minimum-image separation; a callback keeps or drops it, and the kept
//   pairs come out sorted by (i, j). The minimum image is the only image within `cutoff` when the
//   periods are at least 2 cutoff: callers that need all pairs within `cutoff` ensure that.
//   Optionally on a team of OpenMP threads, with the same output.
// - forEachInBox / forEachNear: every periodic image of every stored point inside a region,
//   already shifted next to the query point, so that callers never apply minimum-image
//   conventions themselves. When a period is shorter than the region, several images of one point
//   are reported, each once: that is the correct answer, not a duplicate. Order: layer, row,
//   column (unwrapped indices, ascending), then arrival. Stored positions must lie inside the box
//   along the periodic axes (insert() wraps them; build() stores them as given).
//
// Hand-written rather than FCL's broad phase: FCL's managers hold boxes around objects and know no
// periodic images, and the deposition makes thousands of point queries per second with no
// allocation.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "core/box.hpp"
#include "core/parallel_failure.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace confpack::collision {

using core::BoxDef;
using core::Vec3;

/// A periodic image of a stored point: position = stored position + (shiftX L_x, shiftY W, 0).
struct ImageHit {
  int id = -1;
  int shiftX = 0;
  int shiftY = 0;
  Vec3 position = Vec3::Zero();  ///< [d_L]
};

class CellList {
 public:
  /// build() coarsens the grid past this many cells per point (plus kSpareCells): a real pile has
  /// a few points per cell, a box of a few grains 1e16 wide would otherwise overflow the count.
  static constexpr double kMaxCellsPerPoint = 64.0;
  static constexpr double kSpareCells = 1024.0;
  /// Most cells along x or y, whatever the box: before build() sizes the grid by the points, the
  /// constructor's whole-cutoff counts of a huge box must fit an int (fewer, larger cells find
  /// the same pairs). 2^20 covers any box a run can deposit (max_grains 1e6).
  static constexpr double kMaxCellsPerAxis = 1048576.0;

  /// Cells of at least `cutoff` a side over `box` [d_L]; the layers of insert() start at zMin
  /// [d_L]. Throws std::invalid_argument if the cutoff or a box length is not a positive number.
  CellList(const BoxDef& box, double cutoff, double zMin = 0.0);

  /// Replaces the content by positions[0..n), ids 0..n-1, stored as given (not wrapped). The pair
  /// search also reads `positions` itself (the first point of each pair, in id order): keep them
  /// alive and unchanged until the last findPairs of this build.
  void build(std::span<const Vec3> positions);
  /// Adds one point (stored wrapped into the box). Points below zMin go to the lowest layer.
  void insert(int id, const Vec3& position);
  /// Removes every point, keeps the geometry.
  void clear();

  /// Number of stored points.
  std::size_t size() const { return count_; }
  /// Cell sides [d_L].
  Vec3 cellSize() const { return {hx_, hy_, hz_}; }
  /// Number of cells along x, y and z.
  int cellsX() const { return nx_; }
  int cellsY() const { return ny_; }
  int cellsZ() const { return nz_; }
  const BoxDef& box() const { return box_; }

  /// After build(): bySlot[s] = byId[id stored in slot s], so that a findPairs callback reads the
  /// second point's data in the order the search visits them (its `slot` argument).
  template <class T>
  void toSlotOrder(std::span<const T> byId, std::vector<T>& bySlot) const;

  /// After build(): calls emit(out, i, j, slot, separation, raw) for every pair i < j in the same
  /// or neighbouring cells, where raw = x_j - x_i, separation = its minimum image (the bits of
  /// BoxDef::minimumImage, except that a component -0 stays -0) and slot holds j. emit appends
  /// the pair to `out` or not; the pairs end sorted by i, then by their member `SecondOf` (j).
  /// `out` is cleared first. No allocation once `out` has grown.
  template <auto SecondOf, class Pair, class Emit>
  void findPairs(Emit&& emit, std::vector<Pair>& out) const;

  /// The same on a team of `threads` OpenMP threads (one without OpenMP): contiguous ranges of
  /// first points, thread t > 0 writing teamOut[t], concatenated in order, so the output is
  /// the one-thread output bit for bit. emit must be safe to call concurrently.
  template <auto SecondOf, class Pair, class Emit>
  void findPairs(Emit&& emit, std::vector<Pair>& out, int threads, std::vector<std::vector<Pair>>& teamOut) const;

  /// Calls fn(const ImageHit&) for every periodic image of every stored point lying in the
  /// axis-aligned region [lo, hi] (lo <= hi componentwise; need not lie in the box).
  template <class Fn>
  void forEachInBox(const Vec3& lo, const Vec3& hi, Fn&& fn) const;

  /// Calls fn(const ImageHit&) for every periodic image of every stored point within `radius`
  /// of p (|image - p| <= radius).
  template <class Fn>
  void forEachNear(const Vec3& p, double radius, Fn&& fn) const {
    const Vec3 r = Vec3::Constant(radius);
    const double r2 = radius * radius;
    forEachInBox(p - r, p + r, [&](const ImageHit& hit) {
      if ((hit.position - p).squaredNorm() <= r2) fn(hit);
    });
  }

  /// forEachNear's images in a vector.
  std::vector<ImageHit> near(const Vec3& p, double radius) const;

 private:
  // Free slots given to every cell of a new layer, and the least room after a re-layout.
  static constexpr int kRoom = 4;

  static long floorIndex(double v, double side) { return static_cast<long>(std::floor(v / side)); }
  static long wrapIndex(long i, long n) { return ((i % n) + n) % n; }
  // Index in [0, n) of floor(v): the edge cell beyond either end (and for NaN).
  static int clampIndex(double v, int n) { return v >= n - 1 ? n - 1 : (v > 0.0 ? static_cast<int>(v) : 0); }
  // Cell of coordinate x along a periodic axis (side h, n cells, period L): that of the wrapped
  // coordinate. The first test is the common case of an x inside the period, where wrapping
  // changes nothing.
  static int periodicIndex(double x, double h, int n, double period) {
    const double f = std::floor(x / h);
    if (f >= 0.0 && f < n) return static_cast<int>(f);
    return clampIndex(std::floor(BoxDef::wrapCoordinate(x, period) / h), n);
  }
  int columnOf(double x) const { return periodicIndex(x, hx_, nx_, box_.lengthX); }
  int rowOf(double y) const {
    return box_.periodicY ? periodicIndex(y, hy_, ny_, box_.width) : clampIndex(std::floor(y / hy_), ny_);
  }
  std::size_t cellIndex(long ix, long iy, long iz) const {
    return (static_cast<std::size_t>(iz) * static_cast<std::size_t>(ny_) + static_cast<std::size_t>(iy)) *
               static_cast<std::size_t>(nx_) +
           static_cast<std::size_t>(ix);
  }
  void setColumnsAndRows(double nx, double ny);
  void addLayers(int layers);
  void relayout();
  // The pairs whose first point is in [begin, end), appended to out sorted by (i, j).
  template <auto SecondOf, class Pair, class Emit>
  void pairsOfRange(int begin, int end, Emit& emit, std::vector<Pair>& out) const;

  BoxDef box_;
  double cutoff_ = 1.0;
  double zMin_ = 0.0;
  double hx_ = 1.0, hy_ = 1.0, hz_ = 1.0;
  int nx_ = 1, ny_ = 1, nz_ = 0;
  // Cell c = (iz ny + iy) nx + ix holds slots [first_[c], end_[c]); its room ends at first_[c + 1]
  // (after build(), where end_[c] = first_[c + 1]: the pair search reads first_ alone, as a
  // compressed-row index whose two bounds share a cache line).
  std::vector<int> first_{0};
  std::vector<int> end_;
  std::vector<int> ids_;         // by slot
  std::vector<Vec3> positions_;  // by slot
  std::size_t count_ = 0;
  // The neighbour cells of each cell index along one axis, each once (fewer than 3 cells make a
  // cell its own neighbour twice): neighbours of index c are cells[3 c .. 3 c + count[c]).
  struct AxisNeighbours {
    std::vector<int> cells, count;
    void build(int m, bool periodic);
  };
  // build() only: the points by id, each point's cell, and the neighbours along each axis.
  std::span<const Vec3> points_;
  std::vector<int> cellOf_;
  AxisNeighbours alongX_, alongY_, alongZ_;
};

template <class T>
void CellList::toSlotOrder(std::span<const T> byId, std::vector<T>& bySlot) const {
  bySlot.resize(ids_.size());
  for (std::size_t s = 0; s < ids_.size(); ++s) bySlot[s] = byId[static_cast<std::size_t>(ids_[s])];
}

template <auto SecondOf, class Pair, class Emit>
void CellList::findPairs(Emit&& emit, std::vector<Pair>& out) const {
  out.clear();
  pairsOfRange<SecondOf>(0, static_cast<int>(count_), emit, out);
}

template <auto SecondOf, class Pair, class Emit>
void CellList::findPairs(Emit&& emit, std::vector<Pair>& out, int threads,
                         std::vector<std::vector<Pair>>& teamOut) const {
#ifdef _OPENMP
  if (threads > 1) {
    out.clear();
    const int n = static_cast<int>(count_);
    // First point of chunk t of n points split into `team` contiguous chunks.
    auto chunkBegin = [n](int t, int team) { return static_cast<int>(static_cast<long long>(n) * t / team); };
    if (static_cast<int>(teamOut.size()) < threads) teamOut.resize(static_cast<std::size_t>(threads));
    for (auto& buffer : teamOut) buffer.clear();  // a smaller team leaves some unused
    // A pair list that cannot grow throws std::bad_alloc in a thread: rethrown after the region.
    core::ParallelFailure failure;
#pragma omp parallel num_threads(threads)
    {
      const int t = omp_get_thread_num(), team = omp_get_num_threads();
      failure.capture([&] {
        pairsOfRange<SecondOf>(chunkBegin(t, team), chunkBegin(t + 1, team), emit,
                               t == 0 ? out : teamOut[static_cast<std::size_t>(t)]);
      });
    }
    failure.rethrow();
    for (std::size_t t = 1; t < teamOut.size(); ++t) out.insert(out.end(), teamOut[t].begin(), teamOut[t].end());
    return;
  }
#else
  (void)threads;
  (void)teamOut;
#endif
  findPairs<SecondOf>(emit, out);
}

template <auto SecondOf, class Pair, class Emit>
void CellList::pairsOfRange(int begin, int end, Emit& emit, std::vector<Pair>& out) const {
  // Locals, not members: emit's push_back may call operator new, after which members would be
  // read again.
  const double lx = box_.lengthX, w = box_.width;
  const double halfX = 0.5 * lx, halfY = 0.5 * w;
  const bool periodicY = box_.periodicY;
  const int nx = nx_, ny = ny_;
  const int* cellFirst = first_.data();
  const int* ids = ids_.data();
  const Vec3* positions = positions_.data();
  for (int i = begin; i < end; ++i) {
    const Vec3& p = points_[static_cast<std::size_t>(i)];
    const int c = cellOf_[static_cast<std::size_t>(i)];  // (iz ny + iy) nx + ix
    const int ix = c % nx, iy = (c / nx) % ny, iz = c / (nx * ny);
    const int kx = alongX_.count[static_cast<std::size_t>(ix)], ky = alongY_.count[static_cast<std::size_t>(iy)],
              kz = alongZ_.count[static_cast<std::size_t>(iz)];
    const int* nbx = &alongX_.cells[3 * static_cast<std::size_t>(ix)];
    const int* nby = &alongY_.cells[3 * static_cast<std::size_t>(iy)];
    const int* nbz = &alongZ_.cells[3 * static_cast<std::size_t>(iz)];
    const std::size_t first = out.size();
    for (int a = 0; a < kz; ++a)
      for (int b = 0; b < ky; ++b)
        for (int d = 0; d < kx; ++d) {
          const int cell = (nbz[a] * ny + nby[b]) * nx + nbx[d];
          // Only j > i: a cell's points are ascending, so walk it down from the top and stop at i.
          for (int s = cellFirst[cell + 1] - 1; s >= cellFirst[cell] && ids[s] > i; --s) {
            const Vec3 raw = positions[s] - p;
            // BoxDef::minimumImage(raw), skipping nearbyint where it is exactly 0 (|x| < L/2
            // gives x / L rounded within [-1/2, 1/2], which rounds to 0): same bits, less time.
            // No early rejection along z: that branch went either way about half the time in the
            // nscd broad phase, and the mispredictions cost more than the arithmetic it saved.
            Vec3 sep = raw;
            if (!(std::abs(sep.x()) < halfX)) sep.x() -= lx * std::nearbyint(sep.x() / lx);
            if (periodicY && !(std::abs(sep.y()) < halfY)) sep.y() -= w * std::nearbyint(sep.y() / w);
            emit(out, i, ids[s], s, sep, raw);
          }
        }
    // Sorted by (i, j) whatever the cell layout: the pairs of one i are contiguous and i
    // increases, so sorting each i's few pairs by j sorts the whole list (insertion sort: a
    // handful of pairs, where std::sort's set-up dominates).
    for (std::size_t k = first + 1; k < out.size(); ++k) {
      const Pair x = out[k];
      std::size_t m = k;
      for (; m > first && out[m - 1].*SecondOf > x.*SecondOf; --m) out[m] = out[m - 1];
      out[m] = x;
    }
  }
}

template <class Fn>
void CellList::forEachInBox(const Vec3& lo, const Vec3& hi, Fn&& fn) const {
  if (nz_ == 0 || count_ == 0) return;
  // x: unwrapped cell range; each unwrapped index is one (cell, image shift) pair.
  const long ix0 = floorIndex(lo.x(), hx_), ix1 = floorIndex(hi.x(), hx_);
  long iy0, iy1;
  if (box_.periodicY) {
    iy0 = floorIndex(lo.y(), hy_);
    iy1 = floorIndex(hi.y(), hy_);
  } else {
    // Points outside [0, W] sit in the edge cells; clamping the range keeps them reachable.
    iy0 = std::clamp<long>(floorIndex(lo.y(), hy_), 0, ny_ - 1);
    iy1 = std::clamp<long>(floorIndex(hi.y(), hy_), 0, ny_ - 1);
  }
  const long iz0 = std::clamp<long>(floorIndex(lo.z() - zMin_, hz_), 0, nz_ - 1);
  const long iz1 = std::clamp<long>(floorIndex(hi.z() - zMin_, hz_), 0, nz_ - 1);
  ImageHit hit;
  for (long iz = iz0; iz <= iz1; ++iz) {
    for (long iy = iy0; iy <= iy1; ++iy) {
      long cy = iy;
      hit.shiftY = 0;
      if (box_.periodicY) {
        cy = wrapIndex(iy, ny_);
        hit.shiftY = static_cast<int>((iy - cy) / ny_);
      }
      const double shiftY = static_cast<double>(hit.shiftY) * box_.width;
      for (long ix = ix0; ix <= ix1; ++ix) {
        const long cx = wrapIndex(ix, nx_);
        hit.shiftX = static_cast<int>((ix - cx) / nx_);
        const Vec3 shift(static_cast<double>(hit.shiftX) * box_.lengthX, box_.periodicY ? shiftY : 0.0, 0.0);
        const std::size_t c = cellIndex(cx, cy, iz);
        for (int s = first_[c]; s < end_[c]; ++s) {
          const Vec3 image = positions_[static_cast<std::size_t>(s)] + shift;
          if (image.x() < lo.x() || image.x() > hi.x() || image.y() < lo.y() || image.y() > hi.y() ||
              image.z() < lo.z() || image.z() > hi.z())
            continue;
          hit.id = ids_[static_cast<std::size_t>(s)];
          hit.position = image;
          fn(static_cast<const ImageHit&>(hit));
        }
      }
    }
  }
}

}  // namespace confpack::collision
