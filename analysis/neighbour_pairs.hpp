#pragma once
// Candidate grain pairs by a cell list: every pair whose bounding spheres come within `extra`
// of each other, once, with the minimum-image separation. Linear in the number of grains.
// Apart from core/spatial_grid.hpp, which answers one radius query at a time (the deposition's
// use): this lists every pair once, from one counting sort of the grains into flat arrays.
#include <vector>

#include "core/packing.hpp"

namespace confpack::analysis {

struct NeighbourPair {
  int i = 0;  ///< i < j
  int j = 0;
  core::Vec3 separation = core::Vec3::Zero();  ///< minimum image of x_j - x_i [d_L]
};

/// Pairs with |separation| <= R_i + R_j + extra, R the bounding radii. Assumes the periods are
/// longer than twice the largest interaction range (true for the study's boxes).
std::vector<NeighbourPair> neighbourPairs(const core::Packing& packing, double extra = 0.0);

}  // namespace confpack::analysis
