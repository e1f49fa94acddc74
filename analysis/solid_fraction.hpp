#pragma once
// Solid fraction of the bulk region and its wall-normal profile phi(y) (docs/model.md, "Solid
// fraction" and "Solid-fraction profiles and their fit").
//
// phi = (exact volume of grain material inside the bulk slab zLow < z < zHigh) / (slab volume
// L_x W (zHigh - zLow)). The slab spans the whole period along x and the whole width along y
// (wall to wall, or the y period), so only the two horizontal planes cut grains: a grain's
// contribution is its exact z-slab volume (spherical segment, or the pinacoid clipped by two
// planes), whatever its x, y or periodic image.
//
// phi(y): slices of thickness `slice` (default d_L/50, adjusted so that an integer number tiles
// the width) parallel to the walls. Grains whose centre is in the bulk region (contains(z))
// contribute their exact y-slab volumes (periodic images included when y is periodic); a slice's
// solid fraction is that volume over L_x * slice * (zHigh - zLow). Selecting grains by their
// centre (rather than cutting them at zLow, zHigh as well) keeps the volumes exact slab volumes;
// the mean of the profile differs from the bulk phi only by the few grains straddling the two
// horizontal planes, whose excess and deficit cancel on average.
// With side walls the profile is folded: phi(y) = (phi_raw(y) + phi_raw(W - y)) / 2 for
// 0 <= y <= W/2 (averaged over the two walls); a biperiodic box gives the raw profile.
#include <string_view>
#include <vector>

#include "analysis/bulk_region.hpp"

namespace confpack::analysis {

struct SolidFraction {
  double phi = 0.0;           ///< grain volume / region volume [-]; 0 for an empty region
  double grainVolume = 0.0;   ///< grain material inside the slab [d_L^3]
  double regionVolume = 0.0;  ///< L_x W (zHigh - zLow) [d_L^3]
};

/// Solid fraction of the slab zLow < z < zHigh of `region` (definition above).
SolidFraction solidFraction(const core::Packing& packing, const BulkRegion& region);

struct ProfileDef {
  double slice = 0.02;  ///< target slice thickness [d_L], > 0 (d_L/50)
  bool fold = true;     ///< average the two walls (ignored for a biperiodic box)

  void validate() const;  ///< throws std::invalid_argument naming the bad field
};

struct SolidFractionProfile {
  std::vector<double> y;    ///< slice centres, distance from the wall y = 0 [d_L]
  std::vector<double> phi;  ///< solid fraction of each slice [-]
  double slice = 0.0;       ///< actual slice thickness [d_L]
  bool folded = false;      ///< true: averaged over the two walls, y in [0, W/2]
};

SolidFractionProfile solidFractionProfile(const core::Packing& packing, const BulkRegion& region,
                                          const ProfileDef& def = {});

/// Slice edges 0, dy, ..., W with dy = W / round(W / slice) (at least one slice). Throws
/// std::invalid_argument naming `what` when that is more slices than analysis/cell_count.hpp allows.
std::vector<double> sliceEdges(double width, double slice, std::string_view what = "slice");

/// Folds a profile over [0, W] onto [0, W/2]: f(k) = (raw(k) + raw(n-1-k)) / 2 for k < ceil(n/2).
std::vector<double> foldProfile(const std::vector<double>& raw);

}  // namespace confpack::analysis
