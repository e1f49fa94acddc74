#include "analysis/displacement.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace confpack::analysis {

Displacement displacement(const core::BoxDef& box, const std::vector<core::Grain>& before,
                          const std::vector<core::Grain>& after) {
  if (before.size() != after.size())
    throw std::invalid_argument(
        fmt::format("displacement: {} grains before, {} after: not the same grains", before.size(), after.size()));
  Displacement d;
  double sum = 0.0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const double moved = box.minimumImage(after[i].position - before[i].position).norm();
    sum += moved;
    if (moved > d.max || d.maxGrain < 0) {
      d.max = moved;
      d.maxGrain = static_cast<int>(i);
    }
  }
  if (!before.empty()) d.mean = sum / static_cast<double>(before.size());
  return d;
}

}  // namespace confpack::analysis
