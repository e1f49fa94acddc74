#include "backends/bullet/periodic_pairs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

#include "collision/cell_list.hpp"

namespace confpack::bullet {

PeriodicPairFinder::PeriodicPairFinder(const core::BoxDef& box, double reach) : box_(box), reach_(reach) {
  if (!(reach > 0.0) || !std::isfinite(reach))
    throw std::invalid_argument(fmt::format("periodic pairs: reach must be a positive number (got {})", reach));
  if (box.lengthX <= reach)
    throw std::invalid_argument(fmt::format(
        "box: length_x ({}) must exceed the largest grain size plus the contact threshold ({}) for the bullet backend",
        box.lengthX, reach));
  if (box.periodicY && box.width <= reach)
    throw std::invalid_argument(fmt::format(
        "box: width ({}) must exceed the largest grain size plus the contact threshold ({}) when periodic in y",
        box.width, reach));
}

std::vector<ImagePair> PeriodicPairFinder::find(const std::vector<core::Vec3>& positions,
                                                const std::vector<double>& radii, double threshold) const {
  const int n = static_cast<int>(positions.size());
  const double lx = box_.lengthX, w = box_.width;
  auto nearFace = [&](const core::Vec3& p) {
    if (p.x() < reach_ || p.x() > lx - reach_) return true;
    return box_.periodicY && (p.y() < reach_ || p.y() > w - reach_);
  };
  // Candidates in ascending grain order, so that a < b is k_a < k_b among them.
  std::vector<int> candidates;
  std::vector<core::Vec3> candidatePositions;
  for (int i = 0; i < n; ++i)
    if (nearFace(positions[static_cast<std::size_t>(i)])) {
      candidates.push_back(i);
      candidatePositions.push_back(positions[static_cast<std::size_t>(i)]);
    }
  std::vector<ImagePair> out;
  if (candidates.empty()) return out;
  collision::CellList cells(box_, reach_);
  cells.build(candidatePositions);
  // The query box is a hair wider than the reach, so that rounding in its bounds never drops an
  // image that the exact test below keeps.
  const core::Vec3 halfDiagonal = core::Vec3::Constant(reach_ * (1.0 + 1e-9));
  for (std::size_t ka = 0; ka < candidates.size(); ++ka) {
    const int a = candidates[ka];
    const core::Vec3& pa = positions[static_cast<std::size_t>(a)];
    // Every image of every candidate within the reach of a along each axis; the unshifted ones
    // are Bullet's own pairs.
    cells.forEachInBox(pa - halfDiagonal, pa + halfDiagonal, [&](const collision::ImageHit& hit) {
      if (hit.id <= static_cast<int>(ka) || (hit.shiftX == 0 && hit.shiftY == 0)) return;
      const int b = candidates[static_cast<std::size_t>(hit.id)];
      const core::Vec3 shift(hit.shiftX * lx, hit.shiftY * w, 0.0);
      const double range = radii[static_cast<std::size_t>(a)] + radii[static_cast<std::size_t>(b)] + threshold;
      if ((positions[static_cast<std::size_t>(b)] + shift - pa).squaredNorm() < range * range)
        out.push_back({a, b, hit.shiftX, hit.shiftY, shift});
    });
  }
  std::sort(out.begin(), out.end(), [](const ImagePair& p, const ImagePair& q) {
    return std::tie(p.a, p.b, p.shiftX, p.shiftY) < std::tie(q.a, q.b, q.shiftX, q.shiftY);
  });
  return out;
}

}  // namespace confpack::bullet
