#include "analysis/interpenetration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "analysis/cell_count.hpp"
#include "analysis/grain_volumes.hpp"
#include "analysis/neighbour_pairs.hpp"
#include "analysis/solid_fraction.hpp"
#include "analysis/sphere_geometry.hpp"
#include "core/interrupt.hpp"

namespace confpack::analysis {

void InterpenetrationDef::validate() const {
  if (!(cell > 0.0) || !std::isfinite(cell))
    throw std::invalid_argument(fmt::format("interpenetration: cell must be positive (got {})", cell));
}

namespace {

struct OverlapPair {
  int a = 0, b = 0;
  collision::ConvexPolytope intersection;  // in the slab, in a's frame (unwrapped)
};

// Splits `poly` into the cells of a lattice with origin `origin` and cell sides h, calling
// fn(ix, iy, iz, piece) for every non-empty piece (unwrapped indices). Successive cuts (x slabs,
// then y columns, then z cells), each of an ever smaller polytope, so the cost follows the number
// of cells the polytope actually crosses, not its bounding box.
template <class Fn>
void forEachCellPiece(const collision::ConvexPolytope& poly, const core::Vec3& origin, const core::Vec3& h, Fn&& fn) {
  if (poly.empty()) return;
  const auto [lo, hi] = poly.bounds();
  std::array<int, 3> first{}, last{};
  for (int d = 0; d < 3; ++d) {
    first[d] = static_cast<int>(std::floor((lo[d] - origin[d]) / h[d]));
    last[d] = static_cast<int>(std::floor((hi[d] - origin[d]) / h[d]));
  }
  // Cuts along `axis` from index first..last; level 0 = x, 1 = y, 2 = z.
  std::array<collision::ConvexPolytope, 3> rest, piece, next;
  std::array<int, 3> index{};
  auto sweep = [&](auto&& self, const collision::ConvexPolytope& in, int axis) -> void {
    core::Vec3 e = core::Vec3::Zero();
    e[axis] = 1.0;
    rest[axis] = in;
    for (int i = first[axis]; i <= last[axis] && !rest[axis].empty(); ++i) {
      const double upper = origin[axis] + (i + 1) * h[axis];
      collision::clip(rest[axis], collision::Plane{e, upper}, piece[axis]);
      if (!piece[axis].empty()) {
        index[axis] = i;
        if (axis == 2)
          fn(index[0], index[1], index[2], piece[axis]);
        else
          self(self, piece[axis], axis + 1);
      }
      collision::clip(rest[axis], collision::Plane{-e, -upper}, next[axis]);
      std::swap(rest[axis], next[axis]);
    }
  };
  sweep(sweep, poly, 0);
}

// Lattice bounds (header comment) for the overlapping pinacoid pairs. Returns false (bounds not
// computed) when more than maxCells cells would be visited.
bool latticeBounds(const core::Packing& packing, const BulkRegion& region, const InterpenetrationDef& def,
                   const std::vector<NeighbourPair>& neighbours, const std::vector<OverlapPair>& pairs, double& lower,
                   double& upper, int& cellCount) {
  const core::BoxDef& box = packing.box;
  const int nx = cellsAlong(box.lengthX, def.cell, "interpenetration: lattice cell");
  const int ny = cellsAlong(box.width, def.cell, "interpenetration: lattice cell");
  const int nz = cellsAlong(region.height(), def.cell, "interpenetration: lattice cell");
  const core::Vec3 h(box.lengthX / nx, box.width / ny, region.height() / nz);
  const core::Vec3 origin(0.0, 0.0, region.zLow);
  const double cellVolume = h.prod();

  // (cell key, pair) for every cell that holds part of a pair's overlap, sorted by cell.
  auto key = [&](int ix, int iy, int iz) {
    const std::uint64_t wx = static_cast<std::uint64_t>(((ix % nx) + nx) % nx);
    const std::uint64_t wy =
        static_cast<std::uint64_t>(box.periodicY ? ((iy % ny) + ny) % ny : std::clamp(iy, 0, ny - 1));
    return (static_cast<std::uint64_t>(iz) * ny + wy) * nx + wx;
  };
  std::vector<std::pair<std::uint64_t, int>> entries;
  for (int p = 0; p < static_cast<int>(pairs.size()); ++p) {
    core::stopIfRequested([&] {
      return fmt::format("while cutting overlaps into the interpenetration lattice (pair {} of {})", p + 1,
                         pairs.size());
    });
    forEachCellPiece(pairs[p].intersection, origin, h, [&](int ix, int iy, int iz, const collision::ConvexPolytope&) {
      if (iz < 0 || iz >= nz) return;
      entries.emplace_back(key(ix, iy, iz), p);
    });
    if (entries.size() > def.maxCells) return false;
  }
  std::sort(entries.begin(), entries.end());

  const std::size_t n = packing.grains.size();
  std::vector<std::vector<int>> adjacent(n);
  for (const NeighbourPair& np : neighbours) {
    adjacent[np.i].push_back(np.j);
    adjacent[np.j].push_back(np.i);
  }
  // Each grain's polytope at its own position, built once; a cell is moved into the grain's
  // periodic frame instead of moving the grain.
  std::vector<collision::ConvexPolytope> polytope(n);
  std::vector<std::pair<core::Vec3, core::Vec3>> bounds(n);
  std::vector<char> built(n, 0);
  std::vector<std::size_t> stamp(n, 0);
  std::vector<double> volumeOf(n, 0.0);
  std::vector<int> candidates;
  collision::ConvexPolytope work[2];
  std::size_t cellId = 0;
  for (std::size_t begin = 0; begin < entries.size();) {
    // Each cell clips every grain near it: the longest loop of an analysis of pinacoids.
    core::stopIfRequested([&] {
      return fmt::format("while computing the interpenetration's lattice bounds (cell {}, entry {} of {})", cellId + 1,
                         begin + 1, entries.size());
    });
    std::size_t end = begin;
    while (end < entries.size() && entries[end].first == entries[begin].first) ++end;
    ++cellId;
    const std::uint64_t k = entries[begin].first;
    const int ix = static_cast<int>(k % nx), iy = static_cast<int>((k / nx) % ny),
              iz = static_cast<int>(k / (static_cast<std::uint64_t>(nx) * ny));
    const core::Vec3 lo = origin + core::Vec3(ix * h.x(), iy * h.y(), iz * h.z());
    const core::Vec3 centre = lo + 0.5 * h;
    candidates.clear();
    auto consider = [&](int g) {
      if (stamp[g] == cellId) return;
      stamp[g] = cellId;
      candidates.push_back(g);
    };
    for (std::size_t e = begin; e < end; ++e) {
      for (int g : {pairs[entries[e].second].a, pairs[entries[e].second].b}) {
        consider(g);
        for (int j : adjacent[g]) consider(j);
      }
    }
    double solid = 0.0;
    for (int g : candidates) {
      const core::Grain& grain = packing.grains[g];
      // The cell seen from the grain's own (stored) position.
      const core::Vec3 shift = grain.position - (centre + box.minimumImage(grain.position - centre));
      const core::Vec3 cLo = lo + shift, cHi = lo + h + shift;
      if (!built[g]) {
        const PlacedGrain placed(grain);
        polytope[g] = collision::toPolytope(placed.placed);
        bounds[g] = polytope[g].bounds();
        built[g] = 1;
      }
      volumeOf[g] = 0.0;
      if ((bounds[g].first.array() >= cHi.array()).any() || (bounds[g].second.array() <= cLo.array()).any()) continue;
      const collision::Plane planes[6] = {{core::Vec3::UnitX(), cHi.x()}, {-core::Vec3::UnitX(), -cLo.x()},
                                          {core::Vec3::UnitY(), cHi.y()}, {-core::Vec3::UnitY(), -cLo.y()},
                                          {core::Vec3::UnitZ(), cHi.z()}, {-core::Vec3::UnitZ(), -cLo.z()}};
      collision::clip(polytope[g], planes[0], work[0]);
      int cur = 0;
      for (int pl = 1; pl < 6 && !work[cur].empty(); ++pl) {
        collision::clip(work[cur], planes[pl], work[1 - cur]);
        cur = 1 - cur;
      }
      volumeOf[g] = work[cur].volume();
      solid += volumeOf[g];
    }
    lower += std::max(0.0, solid - cellVolume);
    for (std::size_t e = begin; e < end; ++e) {
      const OverlapPair& op = pairs[entries[e].second];
      upper += std::min(volumeOf[op.a], volumeOf[op.b]);
    }
    ++cellCount;
    begin = end;
  }
  return true;
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
  const collision::Plane below{-core::Vec3::UnitZ(), -region.zLow}, above{core::Vec3::UnitZ(), region.zHigh};
  for (std::size_t k = 0; k < neighbours.size(); ++k) {
    core::stopIfRequested([&] {
      return fmt::format("while computing the interpenetration's overlaps (pair {} of {})", k + 1, neighbours.size());
    });
    const NeighbourPair& np = neighbours[k];
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
      collision::ConvexPolytope inter = pinacoidIntersection(pa.placed, pb.placed);
      if (inter.empty()) continue;
      inter = collision::clipped(collision::clipped(inter, below), above);
      if (inter.empty()) continue;
      const double v = inter.volume();
      if (!(v > 0.0)) continue;
      r.overlapVolume += v;
      ++r.overlappingPairs;
      pinacoidPairs.push_back({np.i, np.j, std::move(inter)});
    }
  }
  const double scale = r.grainVolume > 0.0 ? 100.0 / r.grainVolume : 0.0;
  r.exactPercent = r.overlapVolume * scale;
  if (anyPinacoid && def.lattice) {
    double lower = 0.0, upper = 0.0;
    if (latticeBounds(packing, region, def, neighbours, pinacoidPairs, lower, upper, r.latticeCells)) {
      r.latticeMinPercent = lower * scale;
      r.latticeMaxPercent = upper * scale;
    } else {
      r.latticeSkipped = fmt::format("more than {} lattice cells hold overlap", def.maxCells);
    }
  }
  return r;
}

}  // namespace confpack::analysis
