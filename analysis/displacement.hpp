#pragma once
// How far the grains moved between two packings of the same grains (docs/model.md, "Settling a
// pile from another backend"): what a pile left by one backend had to do to reach rest under
// another. The displacement of a grain is that of its centre, |x_after - x_before| taken as the
// minimum image in the periodic directions [d_L]; rotations are not counted.
#include <vector>

#include "core/box.hpp"
#include "core/grain.hpp"

namespace confpack::analysis {

struct Displacement {
  double max = 0.0;   ///< the largest grain displacement [d_L]
  double mean = 0.0;  ///< over all grains [d_L]
  int maxGrain = -1;  ///< the grain that moved most (-1 without grains)
};

/// Throws std::invalid_argument when the two lists differ in length.
Displacement displacement(const core::BoxDef& box, const std::vector<core::Grain>& before,
                          const std::vector<core::Grain>& after);

}  // namespace confpack::analysis
