#include "analysis/voronoi.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/interrupt.hpp"

#ifdef CONFPACK_HAVE_VORO
#include <voro++/voro++.hh>
#endif

namespace confpack::analysis {

std::optional<VoronoiFraction> voronoiSolidFraction(const core::Packing& packing, const BulkRegion& region) {
#ifndef CONFPACK_HAVE_VORO
  (void)packing;
  (void)region;
  return std::nullopt;
#else
  if (packing.grains.empty() || region.empty()) return std::nullopt;
  double top = 0.0;
  for (const core::Grain& g : packing.grains) {
    if (g.shape != core::ShapeKind::Sphere) return std::nullopt;
    top = std::max(top, g.position.z() + 0.5 * g.size);
  }
  const core::BoxDef& box = packing.box;
  const double zTop = top + 1.0;
  // About 4 grains per block of the container's search grid (voro++ advice: a few per block).
  auto blocks = [](double len) { return std::max(1, static_cast<int>(len / 1.6)); };
  voro::container_poly con(0.0, box.lengthX, 0.0, box.width, 0.0, zTop, blocks(box.lengthX), blocks(box.width),
                           blocks(zTop), true, box.periodicY, false, 8);
  for (int i = 0; i < static_cast<int>(packing.grains.size()); ++i) {
    const core::Grain& g = packing.grains[i];
    core::Vec3 p = box.wrap(g.position);
    // voro++ drops particles outside a non-periodic container; clamp rounding at the walls.
    p.y() = std::clamp(p.y(), 0.0, box.width);
    p.z() = std::clamp(p.z(), 0.0, zTop);
    con.put(i, p.x(), p.y(), p.z(), 0.5 * g.size);
  }
  VoronoiFraction out;
  double solid = 0.0, cellVolume = 0.0;
  voro::c_loop_all loop(con);
  voro::voronoicell cell;
  int visited = 0;
  if (loop.start()) do {
      core::stopIfRequested([&] {
        return fmt::format("while computing the radical Voronoi cells (grain {} of {})", visited + 1,
                           packing.grains.size());
      });
      ++visited;
      const int id = loop.pid();
      const core::Grain& g = packing.grains[id];
      if (!region.contains(g.position.z())) continue;
      if (!con.compute_cell(cell, loop)) continue;
      solid += g.volume();
      cellVolume += cell.volume();
      ++out.cells;
    } while (loop.inc());
  if (!(cellVolume > 0.0)) return std::nullopt;
  out.phi = solid / cellVolume;
  return out;
#endif
}

}  // namespace confpack::analysis
