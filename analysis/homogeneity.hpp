#pragma once
// Homogeneity of a mixture (docs/model.md, "Homogeneity"): fractions P_L and P_S of large and small
// grains in layers of thickness `layer` (d_L) along z (all grains, from the floor) and along y
// (grains of the bulk region, wall to wall), each the number of grains of that size with their
// centre in the layer over the number of grains in the layer. A grain is large when its size
// exceeds `sizeThreshold` (default 0.75 d_L, halfway between d_S = 0.5 and d_L = 1: the 1/30 spread
// truncated at 3 sigma keeps the two populations apart).
#include <vector>

#include "analysis/bulk_region.hpp"

namespace confpack::analysis {

struct HomogeneityDef {
  double layer = 1.0;           ///< layer thickness [d_L], > 0
  double sizeThreshold = 0.75;  ///< large if size > threshold [d_L]
  void validate() const;
};

struct LayerFractions {
  std::vector<double> position;        ///< layer centres [d_L]
  std::vector<int> large, small;       ///< grain counts
  std::vector<double> pLarge, pSmall;  ///< fractions (0 for an empty layer)
};

struct Homogeneity {
  LayerFractions alongZ;
  LayerFractions alongY;
};

Homogeneity homogeneity(const core::Packing& packing, const BulkRegion& region, const HomogeneityDef& def = {});

}  // namespace confpack::analysis
