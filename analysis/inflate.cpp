#include "analysis/inflate.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace confpack::analysis {

void checkInflation(double scale) {
  if (!(scale >= 1.0 && scale <= kMaxInflation) || !std::isfinite(scale))
    throw std::invalid_argument(
        fmt::format("analysis: inflate must be a factor in [1, {}] (got {})", kMaxInflation, scale));
}

core::Packing inflate(const core::Packing& packing, double scale) {
  checkInflation(scale);
  core::Packing out;
  out.box = packing.box;
  out.walls = packing.walls;
  out.grains = packing.grains;
  // A pinacoid's polyhedron is built from its length and its ratios (core/pinacoid.hpp): scaling
  // the length scales every vertex about the centroid.
  for (core::Grain& g : out.grains) g.size *= scale;
  return out;
}

}  // namespace confpack::analysis
