#pragma once
// The free surface and the bulk region of a gravity deposit (docs/model.md, "Bulk region and
// free surface").
//
// Free surface. The top of a pile is rough on the grain scale, so its height is defined as a
// mean: the horizontal box (x over its period, y over the width) is divided into a grid of
// cells of side close to `cellSize` (default 2 d_L: big enough that every cell of a dense pile
// holds several surface grains, small enough to follow a tilted or uneven surface). Each grain
// belongs to the cell of its wrapped centre; in each cell we take the highest point of any grain
// (sphere: centre z + d/2; pinacoid: its highest vertex), and the free-surface height is the mean
// of these maxima over the non-empty cells. Unlike the single highest grain, this mean does not
// jump when one loose grain sits on top.
//
// Bulk region. Grains whose centre lies strictly more than `margin` (3 d_L) above the floor and
// more than `margin` below the free surface: zLow < z < zHigh with zLow = margin and
// zHigh = freeSurface - margin. Along x it spans the period; along y the whole width (wall to
// wall, or the period). Volume-based measurements (solid fraction, interpenetration) use the slab
// zLow < z < zHigh itself; grain-based ones (coordination, homogeneity) use contains(centre z).
#include <nlohmann/json_fwd.hpp>

#include "core/packing.hpp"

namespace confpack::analysis {

struct BulkRegionDef {
  double cellSize = 2.0;  ///< target side of the horizontal cells of the free-surface grid [d_L], > 0
  double margin = 3.0;    ///< clearance from the floor and from the free surface [d_L], >= 0

  void validate() const;  ///< throws std::invalid_argument naming the bad field
};

struct BulkRegion {
  double freeSurface = 0.0;  ///< mean top height of the pile [d_L]
  double zLow = 0.0;         ///< lower bound of the bulk slab [d_L]
  double zHigh = 0.0;        ///< upper bound of the bulk slab [d_L]

  /// True if a grain centre at height z belongs to the bulk (strict inequalities).
  bool contains(double z) const { return z > zLow && z < zHigh; }
  /// Thickness of the slab, 0 when the pile is too low to have a bulk [d_L].
  double height() const { return zHigh > zLow ? zHigh - zLow : 0.0; }
  bool empty() const { return !(zHigh > zLow); }
  /// Volume of the slab: L_x * W * height [d_L^3].
  double volume(const core::BoxDef& box) const { return box.lengthX * box.width * height(); }
};

/// Highest point of a grain [d_L].
double grainTop(const core::Grain& g);
/// Lowest point of a grain [d_L].
double grainBottom(const core::Grain& g);

/// Free-surface height of the packing (definition above) [d_L]; 0 for an empty packing.
double freeSurfaceHeight(const core::Packing& packing, double cellSize = 2.0);

/// Free surface and bulk slab of a packing.
BulkRegion bulkRegion(const core::Packing& packing, const BulkRegionDef& def = {});

void to_json(nlohmann::json& j, const BulkRegion& r);

}  // namespace confpack::analysis
