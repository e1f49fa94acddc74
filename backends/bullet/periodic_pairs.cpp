#include "backends/bullet/periodic_pairs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace confpack::bullet {

namespace {
// Cells needed along a periodic length so that cell i and cell j are neighbours in one way only
// (i+1 and i-1 distinct modulo n).
constexpr int kMinPeriodicCells = 3;
}  // namespace

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
  cellsX_ = static_cast<int>(std::floor(box.lengthX / reach));
  if (cellsX_ < kMinPeriodicCells) cellsX_ = 0;
  if (box.periodicY) {
    cellsY_ = static_cast<int>(std::floor(box.width / reach));
    if (cellsY_ < kMinPeriodicCells) cellsY_ = 0;
  }
}

std::vector<ImagePair> PeriodicPairFinder::find(const std::vector<core::Vec3>& positions,
                                                const std::vector<double>& radii, double threshold) const {
  const int n = static_cast<int>(positions.size());
  const double lx = box_.lengthX, w = box_.width;
  auto nearFace = [&](const core::Vec3& p) {
    if (p.x() < reach_ || p.x() > lx - reach_) return true;
    return box_.periodicY && (p.y() < reach_ || p.y() > w - reach_);
  };
  std::vector<int> candidates;
  for (int i = 0; i < n; ++i)
    if (nearFace(positions[i])) candidates.push_back(i);

  std::vector<ImagePair> out;
  auto consider = [&](int a, int b, int sx, int sy) {
    const core::Vec3 shift(sx * lx, sy * w, 0.0);
    const double range = radii[a] + radii[b] + threshold;
    if ((positions[b] + shift - positions[a]).squaredNorm() < range * range) out.push_back({a, b, sx, sy, shift});
  };

  const bool bruteForce = cellsX_ == 0 || (box_.periodicY && cellsY_ == 0);
  if (bruteForce) {
    // Short box: every candidate pair against every non-trivial image (the direct pair is
    // Bullet's). Only small systems get here.
    const int syMax = box_.periodicY ? 1 : 0;
    for (std::size_t i = 0; i < candidates.size(); ++i)
      for (std::size_t j = i + 1; j < candidates.size(); ++j)
        for (int sx = -1; sx <= 1; ++sx)
          for (int sy = -syMax; sy <= syMax; ++sy)
            if (sx != 0 || sy != 0) consider(candidates[i], candidates[j], sx, sy);
  } else {
    // Periodic cell list over the candidates only. Cells are at least `reach` wide, so a
    // touching pair sits in neighbouring cells; with >= 3 cells per periodic direction the
    // neighbour relation is unique and the minimum image is the only image in reach.
    const int nx = cellsX_;
    const int ny = box_.periodicY ? cellsY_ : std::max(1, static_cast<int>(std::floor(w / reach_)));
    double zMin = 0.0, zMax = 0.0;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      const double z = positions[candidates[k]].z();
      zMin = k == 0 ? z : std::min(zMin, z);
      zMax = k == 0 ? z : std::max(zMax, z);
    }
    const int nz = static_cast<int>(std::floor((zMax - zMin) / reach_)) + 1;
    auto cellOf = [&](const core::Vec3& p) {
      const int ix = std::clamp(static_cast<int>(std::floor(p.x() / lx * nx)), 0, nx - 1);
      const int iy = std::clamp(static_cast<int>(std::floor(p.y() / w * ny)), 0, ny - 1);
      const int iz = std::clamp(static_cast<int>(std::floor((p.z() - zMin) / reach_)), 0, nz - 1);
      return std::make_tuple(ix, iy, iz);
    };
    auto flat = [&](int ix, int iy, int iz) { return (static_cast<std::size_t>(iz) * ny + iy) * nx + ix; };
    // Counting sort of candidates by cell: start offsets, then members.
    const std::size_t cellCount = static_cast<std::size_t>(nx) * ny * nz;
    std::vector<int> start(cellCount + 1, 0), members(candidates.size());
    for (int i : candidates) {
      auto [ix, iy, iz] = cellOf(positions[i]);
      ++start[flat(ix, iy, iz) + 1];
    }
    for (std::size_t c = 0; c < cellCount; ++c) start[c + 1] += start[c];
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int i : candidates) {
      auto [ix, iy, iz] = cellOf(positions[i]);
      members[fill[flat(ix, iy, iz)]++] = i;
    }
    for (int a : candidates) {
      auto [ix, iy, iz] = cellOf(positions[a]);
      for (int dz = -1; dz <= 1; ++dz) {
        const int jz = iz + dz;
        if (jz < 0 || jz >= nz) continue;
        for (int dy = -1; dy <= 1; ++dy) {
          int jy = iy + dy;
          if (box_.periodicY)
            jy = (jy + ny) % ny;
          else if (jy < 0 || jy >= ny)
            continue;
          for (int dx = -1; dx <= 1; ++dx) {
            const int jx = (ix + dx + nx) % nx;
            const std::size_t c = flat(jx, jy, jz);
            for (int k = start[c]; k < start[c + 1]; ++k) {
              const int b = members[k];
              if (b <= a) continue;
              const core::Vec3 d = positions[b] - positions[a];
              const core::Vec3 m = box_.minimumImage(d);
              const int sx = static_cast<int>(std::lround((m.x() - d.x()) / lx));
              const int sy = box_.periodicY ? static_cast<int>(std::lround((m.y() - d.y()) / w)) : 0;
              if (sx != 0 || sy != 0) consider(a, b, sx, sy);
            }
          }
        }
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const ImagePair& p, const ImagePair& q) {
    return std::tie(p.a, p.b, p.shiftX, p.shiftY) < std::tie(q.a, q.b, q.shiftX, q.shiftY);
  });
  return out;
}

}  // namespace confpack::bullet
