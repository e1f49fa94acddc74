#pragma once
// A uniform cell grid over the box (docs/model.md, "Box") for neighbour queries of points (grain
// centres, placeholder centres). Cells are at least `minCellSize` on every side, so a query of
// radius r visits about (2 r / cell + 1)^3 cells whatever the number of points: a deposit or a
// contact search built on it is linear in n.
//
// Periodicity is the grid's business, not the caller's: x is periodic (period lengthX), y is
// periodic when the box says so, z is open upwards (layers are added as points arrive) and starts
// at `zMin`. A query hands back every periodic image of a stored point that falls in the query
// region, already shifted next to the query point, so callers never apply minimum-image
// conventions themselves. When the period is shorter than the query range (tiny boxes), several
// images of one point are returned, each once: that is the correct answer, not a duplicate.
//
// Hand-written rather than FCL's broad phase: FCL's managers are for boxes around objects, have
// no notion of periodic images, and the deposition needs thousands of point queries per second
// with no allocation.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "core/box.hpp"

namespace confpack::core {

class SpatialGrid {
 public:
  /// A stored point: caller's id and its position wrapped into the box.
  struct Entry {
    int id = -1;
    Vec3 position = Vec3::Zero();
  };

  /// Grid over `box` with cells of side >= minCellSize [d_L]; z cells start at zMin [d_L].
  /// Throws std::invalid_argument if minCellSize is not positive.
  SpatialGrid(const BoxDef& box, double minCellSize, double zMin = 0.0);

  /// Stores a point (wrapped into the box first). Points below zMin go to the lowest layer.
  void insert(int id, const Vec3& position);
  /// Removes every point, keeps the geometry.
  void clear();
  /// Number of stored points.
  std::size_t size() const { return count_; }
  /// Cell sides [d_L].
  Vec3 cellSize() const { return {cellX_, cellY_, cellZ_}; }
  /// Number of cells along x, y and z (z grows with the points).
  int cellsX() const { return nx_; }
  int cellsY() const { return ny_; }
  int cellsZ() const { return nz_; }
  const BoxDef& box() const { return box_; }

  /// Calls fn(id, image) for every periodic image of every stored point lying in the
  /// axis-aligned region [lo, hi] (positions need not be wrapped; lo <= hi componentwise).
  template <class Fn>
  void forEachInBox(const Vec3& lo, const Vec3& hi, Fn&& fn) const;

  /// Calls fn(id, image) for every periodic image of every stored point within `radius` of p
  /// (|image - p| <= radius).
  template <class Fn>
  void forEachNear(const Vec3& p, double radius, Fn&& fn) const {
    const Vec3 r = Vec3::Constant(radius);
    const double r2 = radius * radius;
    forEachInBox(p - r, p + r, [&](int id, const Vec3& image) {
      if ((image - p).squaredNorm() <= r2) fn(id, image);
    });
  }

  /// Convenience form of forEachNear: (id, image) pairs in storage order.
  std::vector<Entry> near(const Vec3& p, double radius) const {
    std::vector<Entry> out;
    forEachNear(p, radius, [&](int id, const Vec3& image) { out.push_back({id, image}); });
    return out;
  }

 private:
  static long floorIndex(double v, double cell) { return static_cast<long>(std::floor(v / cell)); }
  static long wrapIndex(long i, long n) { return ((i % n) + n) % n; }
  int layerOf(double z) const;
  std::size_t cellIndex(long ix, long iy, long iz) const {
    return (static_cast<std::size_t>(iz) * static_cast<std::size_t>(ny_) + static_cast<std::size_t>(iy)) *
               static_cast<std::size_t>(nx_) +
           static_cast<std::size_t>(ix);
  }

  BoxDef box_;
  double zMin_ = 0.0;
  double cellX_ = 1.0, cellY_ = 1.0, cellZ_ = 1.0;
  int nx_ = 1, ny_ = 1, nz_ = 0;
  std::vector<std::vector<Entry>> cells_;  // index (iz * ny + iy) * nx + ix
  std::size_t count_ = 0;
};

template <class Fn>
void SpatialGrid::forEachInBox(const Vec3& lo, const Vec3& hi, Fn&& fn) const {
  if (nz_ == 0 || count_ == 0) return;
  // x: unwrapped cell range; each unwrapped index is one (cell, image shift) pair.
  const long ix0 = floorIndex(lo.x(), cellX_), ix1 = floorIndex(hi.x(), cellX_);
  long iy0, iy1;
  if (box_.periodicY) {
    iy0 = floorIndex(lo.y(), cellY_);
    iy1 = floorIndex(hi.y(), cellY_);
  } else {
    // Points outside [0, W] sit in the edge cells; clamping the range keeps them reachable.
    iy0 = std::clamp<long>(floorIndex(lo.y(), cellY_), 0, ny_ - 1);
    iy1 = std::clamp<long>(floorIndex(hi.y(), cellY_), 0, ny_ - 1);
  }
  const long iz0 = std::clamp<long>(floorIndex(lo.z() - zMin_, cellZ_), 0, nz_ - 1);
  const long iz1 = std::clamp<long>(floorIndex(hi.z() - zMin_, cellZ_), 0, nz_ - 1);
  for (long iz = iz0; iz <= iz1; ++iz) {
    for (long iy = iy0; iy <= iy1; ++iy) {
      long cy = iy;
      double shiftY = 0.0;
      if (box_.periodicY) {
        cy = wrapIndex(iy, ny_);
        shiftY = static_cast<double>((iy - cy) / ny_) * box_.width;
      }
      for (long ix = ix0; ix <= ix1; ++ix) {
        const long cx = wrapIndex(ix, nx_);
        const Vec3 shift(static_cast<double>((ix - cx) / nx_) * box_.lengthX, shiftY, 0.0);
        for (const Entry& e : cells_[cellIndex(cx, cy, iz)]) {
          const Vec3 image = e.position + shift;
          if (image.x() < lo.x() || image.x() > hi.x() || image.y() < lo.y() || image.y() > hi.y() ||
              image.z() < lo.z() || image.z() > hi.z())
            continue;
          fn(e.id, image);
        }
      }
    }
  }
}

}  // namespace confpack::core
