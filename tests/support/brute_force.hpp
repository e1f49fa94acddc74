#pragma once
// O(n^2) references for the cell list (collision::CellList) and its users (nscd::BroadPhase,
// bullet::PeriodicPairFinder, analysis::neighbourPairs): every periodic image is tried, so a
// search that misses or duplicates one shows up as a difference.
#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "core/box.hpp"

namespace confpack::testing {

/// An image of stored point `id` at the given coordinates.
using ImageHit = std::tuple<int, double, double, double>;

/// (a, b, shiftX, shiftY): grain b's image at p_b + (shiftX L_x, shiftY W, 0) is near grain a.
using ImagePairKey = std::tuple<int, int, int, int>;

/// Number of periods to try on each side along one direction so that every image within `reach`
/// of a point at most `extent` away from the box is tried.
inline int periodsToTry(double reach, double extent, double period) {
  return static_cast<int>(std::ceil((reach + extent + period) / period)) + 1;
}

/// Every image p_id + (i L_x, j W, 0) (j = 0 unless periodic in y) of every point within r of p
/// (|image - p| <= r), sorted.
inline std::vector<ImageHit> imagesNear(const core::BoxDef& box, const std::vector<core::Vec3>& pts,
                                        const core::Vec3& p, double r) {
  std::vector<ImageHit> out;
  const int kx = periodsToTry(r, std::abs(p.x()), box.lengthX);
  const int ky = box.periodicY ? periodsToTry(r, std::abs(p.y()), box.width) : 0;
  for (std::size_t id = 0; id < pts.size(); ++id)
    for (int i = -kx; i <= kx; ++i)
      for (int j = -ky; j <= ky; ++j) {
        const core::Vec3 image = pts[id] + core::Vec3(i * box.lengthX, j * box.width, 0.0);
        if ((image - p).norm() <= r) out.emplace_back(static_cast<int>(id), image.x(), image.y(), image.z());
      }
  std::sort(out.begin(), out.end());
  return out;
}

/// Every pair a < b and image shift with |p_b + shift - p_a| < radius_a + radius_b + threshold,
/// over all periodic images (positions may lie up to one period outside the box).
/// `withUnshifted` = false leaves out the shift (0, 0): the pairs that touch across a face only.
inline std::set<ImagePairKey> pairsWithin(const core::BoxDef& box, const std::vector<core::Vec3>& p,
                                          const std::vector<double>& radius, double threshold = 0.0,
                                          bool withUnshifted = true) {
  std::set<ImagePairKey> out;
  const int kx = 2;
  const int ky = box.periodicY ? 2 : 0;
  const int n = static_cast<int>(p.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      for (int i = -kx; i <= kx; ++i)
        for (int j = -ky; j <= ky; ++j) {
          if (i == 0 && j == 0 && !withUnshifted) continue;
          const core::Vec3 shift(i * box.lengthX, j * box.width, 0.0);
          if ((p[b] + shift - p[a]).norm() < radius[a] + radius[b] + threshold) out.insert({a, b, i, j});
        }
  return out;
}

/// Every pair (a, b), a < b, whose closest periodic image lies within `cutoff` (|d| < cutoff),
/// sorted by (a, b): the order collision::CellList::findPairs documents. Positions may lie up to
/// one period outside the box.
inline std::vector<std::pair<int, int>> pairsWithinCutoff(const core::BoxDef& box, const std::vector<core::Vec3>& p,
                                                          double cutoff) {
  std::vector<std::pair<int, int>> out;
  const int ky = box.periodicY ? 2 : 0;
  const int n = static_cast<int>(p.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      double closest = 1e300;
      for (int i = -2; i <= 2; ++i)
        for (int j = -ky; j <= ky; ++j)
          closest = std::min(closest, (p[b] + core::Vec3(i * box.lengthX, j * box.width, 0.0) - p[a]).norm());
      if (closest < cutoff) out.emplace_back(a, b);
    }
  return out;
}

}  // namespace confpack::testing
