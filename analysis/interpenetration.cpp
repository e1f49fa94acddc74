#include "analysis/interpenetration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "analysis/grain_volumes.hpp"
#include "analysis/neighbour_pairs.hpp"
#include "analysis/solid_fraction.hpp"
#include "analysis/sphere_geometry.hpp"

namespace confpack::analysis {

void InterpenetrationDef::validate() const {
  if (!(cell > 0.0) || !std::isfinite(cell))
    throw std::invalid_argument(fmt::format("interpenetration: cell must be positive (got {})", cell));
}

namespace {

struct OverlapPair {
  int a = 0, b = 0;
  core::Vec3 separation;
  core::Vec3 lo, hi;  // bounds of the in-slab intersection, in a's frame
};

// Lattice bounds (header comment) for the overlapping pinacoid pairs.
void latticeBounds(const core::Packing& packing, const BulkRegion& region, const InterpenetrationDef& def,
                   const std::vector<NeighbourPair>& neighbours, const std::vector<OverlapPair>& pairs,
                   double& lower, double& upper, int& cellCount) {
  const core::BoxDef& box = packing.box;
  const int nx = std::max(1, static_cast<int>(std::lround(box.lengthX / def.cell)));
  const int ny = std::max(1, static_cast<int>(std::lround(box.width / def.cell)));
  const int nz = std::max(1, static_cast<int>(std::lround(region.height() / def.cell)));
  const core::Vec3 h(box.lengthX / nx, box.width / ny, region.height() / nz);
  const double cellVolume = h.prod();

  // Cells that can hold overlap, each with the pairs whose intersection box reaches it.
  std::map<std::tuple<int, int, int>, std::vector<int>> cells;
  for (int p = 0; p < static_cast<int>(pairs.size()); ++p) {
    const OverlapPair& op = pairs[p];
    const int x0 = static_cast<int>(std::floor(op.lo.x() / h.x())), x1 = static_cast<int>(std::floor(op.hi.x() / h.x()));
    const int y0 = static_cast<int>(std::floor(op.lo.y() / h.y())), y1 = static_cast<int>(std::floor(op.hi.y() / h.y()));
    const int z0 = std::max(0, static_cast<int>(std::floor((op.lo.z() - region.zLow) / h.z())));
    const int z1 = std::min(nz - 1, static_cast<int>(std::floor((op.hi.z() - region.zLow) / h.z())));
    for (int iz = z0; iz <= z1; ++iz)
      for (int iy = y0; iy <= y1; ++iy)
        for (int ix = x0; ix <= x1; ++ix) {
          const int wx = ((ix % nx) + nx) % nx;
          int wy = iy;
          if (box.periodicY) wy = ((iy % ny) + ny) % ny;
          else if (iy < 0 || iy >= ny) continue;  // outside the walls: no grain material there
          cells[{wx, wy, iz}].push_back(p);
        }
  }

  // Neighbour lists, to find every grain that reaches a cell.
  std::vector<std::vector<int>> adjacent(packing.grains.size());
  for (const NeighbourPair& np : neighbours) {
    adjacent[np.i].push_back(np.j);
    adjacent[np.j].push_back(np.i);
  }
  std::vector<std::optional<PlacedGrain>> placed(packing.grains.size());
  std::vector<int> candidates;
  std::map<int, double> volumeOf;
  for (const auto& [key, pairList] : cells) {
    const auto [ix, iy, iz] = key;
    const core::Vec3 lo(ix * h.x(), iy * h.y(), region.zLow + iz * h.z());
    const core::Vec3 hi = lo + h;
    const core::Vec3 centre = 0.5 * (lo + hi);
    const double halfDiagonal = 0.5 * h.norm();
    candidates.clear();
    for (int p : pairList) {
      for (int g : {pairs[p].a, pairs[p].b}) {
        candidates.push_back(g);
        candidates.insert(candidates.end(), adjacent[g].begin(), adjacent[g].end());
      }
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    volumeOf.clear();
    double solid = 0.0;
    for (int g : candidates) {
      const core::Grain& grain = packing.grains[g];
      const core::Vec3 image = centre + box.minimumImage(grain.position - centre);
      if ((image - centre).norm() > grain.boundingRadius() + halfDiagonal) continue;
      if (!placed[g]) placed[g].emplace(grain);
      core::PlacedPolyhedron at = placed[g]->placed;
      at.position = image;
      const double v = core::boxVolume(at, lo, hi);
      volumeOf[g] = v;
      solid += v;
    }
    lower += std::max(0.0, solid - cellVolume);
    for (int p : pairList) {
      const auto va = volumeOf.find(pairs[p].a), vb = volumeOf.find(pairs[p].b);
      if (va != volumeOf.end() && vb != volumeOf.end()) upper += std::min(va->second, vb->second);
    }
    ++cellCount;
  }
}

}  // namespace

Interpenetration interpenetration(const core::Packing& packing, const BulkRegion& region,
                                  const InterpenetrationDef& def) {
  def.validate();
  Interpenetration r;
  r.grainVolume = solidFraction(packing, region).grainVolume;
  if (region.empty() || packing.grains.empty()) return r;
  const std::vector<NeighbourPair> neighbours = neighbourPairs(packing);
  std::vector<OverlapPair> pinacoidPairs;
  bool anyPinacoid = false;
  for (const core::Grain& g : packing.grains) anyPinacoid = anyPinacoid || g.shape == core::ShapeKind::Pinacoid;
  const core::Plane below{-core::Vec3::UnitZ(), -region.zLow}, above{core::Vec3::UnitZ(), region.zHigh};
  for (const NeighbourPair& np : neighbours) {
    const core::Grain& a = packing.grains[np.i];
    const core::Grain& b = packing.grains[np.j];
    if (a.shape != b.shape)
      throw std::invalid_argument("interpenetration: mixed sphere-pinacoid packings are not supported");
    if (a.shape == core::ShapeKind::Sphere) {
      const double r1 = 0.5 * a.size, r2 = 0.5 * b.size, d = np.separation.norm();
      const double v = sphereLensVolume(r1, r2, d);
      if (!(v > 0.0)) continue;
      // Lens centre: the radical plane crosses the line of centres at x from a's centre.
      const double x = d > 0.0 ? (d * d + r1 * r1 - r2 * r2) / (2.0 * d) : 0.0;
      const double zc = a.position.z() + (d > 0.0 ? np.separation.z() * x / d : 0.0);
      r.maxSphereDepth = std::max(r.maxSphereDepth, r1 + r2 - d);
      if (!region.contains(zc)) continue;
      r.overlapVolume += v;
      ++r.overlappingPairs;
    } else {
      const PlacedGrain pa(a), pb(b, a.position + np.separation);
      core::ConvexPolytope inter = pinacoidIntersection(pa.placed, pb.placed);
      if (inter.empty()) continue;
      inter = core::clipped(core::clipped(inter, below), above);
      if (inter.empty()) continue;
      const double v = inter.volume();
      if (!(v > 0.0)) continue;
      r.overlapVolume += v;
      ++r.overlappingPairs;
      const auto [lo, hi] = inter.bounds();
      pinacoidPairs.push_back({np.i, np.j, np.separation, lo, hi});
    }
  }
  const double scale = r.grainVolume > 0.0 ? 100.0 / r.grainVolume : 0.0;
  r.exactPercent = r.overlapVolume * scale;
  if (anyPinacoid && def.lattice) {
    double lower = 0.0, upper = 0.0;
    latticeBounds(packing, region, def, neighbours, pinacoidPairs, lower, upper, r.latticeCells);
    r.latticeMinPercent = lower * scale;
    r.latticeMaxPercent = upper * scale;
  }
  return r;
}

}  // namespace confpack::analysis
