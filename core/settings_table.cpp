#include "core/settings_table.hpp"

namespace confpack::core {

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  const bool aboveLow = lowOpen ? v > low : v >= low;
  const bool belowHigh = highOpen ? v < high : v <= high;
  return aboveLow && belowHigh;
}

std::string numberText(double v) {
  return fmt::format("{:g}", v);
}

std::string Range::text() const {
  const bool hasLow = std::isfinite(low), hasHigh = std::isfinite(high);
  if (hasLow && hasHigh)
    return fmt::format("in {}{}, {}{}", lowOpen ? '(' : '[', numberText(low), numberText(high), highOpen ? ')' : ']');
  if (hasLow) return fmt::format("{} {}", lowOpen ? ">" : ">=", numberText(low));
  if (hasHigh) return fmt::format("{} {}", highOpen ? "<" : "<=", numberText(high));
  return "a finite number";
}

}  // namespace confpack::core
