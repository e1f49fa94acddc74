#include "analysis/bulk_region.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "analysis/cell_count.hpp"

namespace confpack::analysis {

void BulkRegionDef::validate() const {
  if (!(cellSize > 0.0) || !std::isfinite(cellSize))
    throw std::invalid_argument(fmt::format("bulk region: cell_size must be positive (got {})", cellSize));
  if (!(margin >= 0.0) || !std::isfinite(margin))
    throw std::invalid_argument(fmt::format("bulk region: margin must be >= 0 (got {})", margin));
}

namespace {
// Extreme vertex height of a pinacoid along +z (sign = +1) or -z (sign = -1).
double pinacoidExtremeZ(const core::Grain& g, double sign) {
  double best = -std::numeric_limits<double>::infinity();
  for (const core::Vec3& v : g.worldVertices()) best = std::max(best, sign * v.z());
  return sign * best;
}
}  // namespace

double grainTop(const core::Grain& g) {
  if (g.shape == core::ShapeKind::Sphere) return g.position.z() + 0.5 * g.size;
  return pinacoidExtremeZ(g, 1.0);
}

double grainBottom(const core::Grain& g) {
  if (g.shape == core::ShapeKind::Sphere) return g.position.z() - 0.5 * g.size;
  return pinacoidExtremeZ(g, -1.0);
}

double freeSurfaceHeight(const core::Packing& packing, double cellSize) {
  if (packing.grains.empty()) return 0.0;
  const core::BoxDef& box = packing.box;
  const int nx = cellsAlong(box.lengthX, cellSize, "free surface: cell");
  const int ny = cellsAlong(box.width, cellSize, "free surface: cell");
  const double cx = box.lengthX / nx, cy = box.width / ny;
  std::vector<double> top(static_cast<std::size_t>(nx) * ny, -std::numeric_limits<double>::infinity());
  for (const core::Grain& g : packing.grains) {
    const core::Vec3 p = box.wrap(g.position);
    // Clamp: with walls a centre sits inside [0, W]; the clamp only guards rounding at the edges.
    const int ix = std::clamp(static_cast<int>(std::floor(p.x() / cx)), 0, nx - 1);
    const int iy = std::clamp(static_cast<int>(std::floor(p.y() / cy)), 0, ny - 1);
    double& t = top[static_cast<std::size_t>(iy) * nx + ix];
    t = std::max(t, grainTop(g));
  }
  double sum = 0.0;
  int filled = 0;
  for (double t : top)
    if (std::isfinite(t)) {
      sum += t;
      ++filled;
    }
  return filled > 0 ? sum / filled : 0.0;
}

BulkRegion bulkRegion(const core::Packing& packing, const BulkRegionDef& def) {
  def.validate();
  BulkRegion r;
  r.freeSurface = freeSurfaceHeight(packing, def.cellSize);
  r.zLow = def.margin;
  r.zHigh = r.freeSurface - def.margin;
  return r;
}

void to_json(nlohmann::json& j, const BulkRegion& r) {
  j = {{"free_surface", r.freeSurface}, {"z_low", r.zLow}, {"z_high", r.zHigh}, {"empty", r.empty()}};
}

}  // namespace confpack::analysis
