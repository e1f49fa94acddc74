#pragma once
// Candidate grain pairs for the analysis: every pair whose bounding spheres come within `extra`
// of each other, once, with the minimum-image separation. A pair search of the shared cell list
// (collision/cell_list.hpp), linear in the number of grains.
#include <vector>

#include "core/packing.hpp"

namespace confpack::analysis {

struct NeighbourPair {
  int i = 0;  ///< i < j
  int j = 0;
  core::Vec3 separation = core::Vec3::Zero();  ///< minimum image of x_j - x_i [d_L]
};

/// Pairs with |separation| <= R_i + R_j + extra, R the bounding radii, sorted by (i, j). Assumes
/// the periods are longer than twice the largest interaction range (true for the study's boxes).
std::vector<NeighbourPair> neighbourPairs(const core::Packing& packing, double extra = 0.0);

}  // namespace confpack::analysis
