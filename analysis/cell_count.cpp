#include "analysis/cell_count.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace confpack::analysis {

int cellsAlong(double length, double side, std::string_view what) {
  const double count = std::round(length / side);
  // Negated so that a NaN count is refused too.
  if (!(count <= kMaxCellsAlongAxis))
    throw std::invalid_argument(fmt::format(
        "{} of {:g} d_L over {:g} d_L makes {:.3g} cells, more than the {:g} one axis can hold; give a larger one",
        what, side, length, count, kMaxCellsAlongAxis));
  return std::max(1, static_cast<int>(count));
}

}  // namespace confpack::analysis
