// Fuzz target: the plausibility check of analyze and run --from (analysis/plausibility.hpp) on every
// packing the reader accepts, held against a brute-force oracle. Whatever the cell list and the
// geometric contacts find, a packing must be refused when, over all pairs by their minimum image,
// - two grains of one shape share a centre (distance 0: the deepest overlap there is),
// - two spheres, or a sphere and the floor or a side wall, overlap deeper than the limit
//   (PlausibilityDef::maxOverlapFraction of the smaller size, with a margin for rounding),
// - or a grain is larger than the box.
// The seeds (fuzz/corpus/plausibility/) are the geometric edge cases: coincident centres, one
// grain inside another, grains touching or overlapping by 1e-15, a grain 1e-15 through a wall,
// centres 1e-15 apart across the period.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "analysis/plausibility.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_packing_input.hpp"

namespace {

using namespace confpack;

// The oracle visits every pair: beyond this many grains an input only costs time.
constexpr std::size_t kMaxOracleGrains = 256;
// Depths this close to the limit may round either way in the two computations.
constexpr double kRelativeMargin = 1e-9;

/// Why the oracle says `p` must be implausible, or nullopt when it says nothing.
std::optional<std::string> mustBeImplausible(const core::Packing& p) {
  const analysis::PlausibilityDef def;
  const core::BoxDef& box = p.box;
  auto tooDeep = [&](double depth, double smaller) {
    return depth > def.maxOverlapFraction * smaller * (1.0 + kRelativeMargin) + 1e-12;
  };
  for (std::size_t i = 0; i < p.grains.size(); ++i) {
    const core::Grain& a = p.grains[i];
    if (a.size > box.lengthX || a.size > box.width || a.size > box.height)
      return "grain " + std::to_string(i) + " is larger than the box";
  }
  for (std::size_t i = 0; i < p.grains.size(); ++i) {
    const core::Grain& a = p.grains[i];
    if (a.shape == core::ShapeKind::Sphere) {
      if (tooDeep(0.5 * a.size - a.position.z(), a.size)) return "sphere " + std::to_string(i) + " deep in the floor";
      if (!box.periodicY && (tooDeep(0.5 * a.size - a.position.y(), a.size) ||
                             tooDeep(0.5 * a.size - (box.width - a.position.y()), a.size)))
        return "sphere " + std::to_string(i) + " deep in a side wall";
    }
    for (std::size_t j = i + 1; j < p.grains.size(); ++j) {
      const core::Grain& b = p.grains[j];
      if (a.shape != b.shape) continue;
      const double distance = box.minimumImage(b.position - a.position).norm();
      if (distance == 0.0) return "grains " + std::to_string(i) + " and " + std::to_string(j) + " share a centre";
      if (a.shape == core::ShapeKind::Sphere && tooDeep(0.5 * (a.size + b.size) - distance, std::min(a.size, b.size)))
        return "spheres " + std::to_string(i) + " and " + std::to_string(j) + " overlap too deep";
    }
  }
  return std::nullopt;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::optional<core::Packing> accepted = fuzz::acceptedPacking(data, size);
  if (!accepted) return 0;
  const core::Packing& packing = *accepted;
  bool mixed = false;
  for (const core::Grain& g : packing.grains) mixed = mixed || g.shape != packing.grains.front().shape;
  std::optional<std::string> why;
  try {
    why = analysis::implausibility(packing);
  } catch (const std::invalid_argument& e) {
    // Only a packing mixing spheres and pinacoids may be refused outright (the commands refuse it
    // before, analysis::checkPlausible).
    fuzz::require(mixed, "implausibility threw on a packing of one shape", e.what());
    fuzz::checkRefusal(e);
    return 0;
  }
  if (mixed || packing.grains.size() > kMaxOracleGrains) return 0;
  if (const std::optional<std::string> oracle = mustBeImplausible(packing))
    fuzz::require(why.has_value(), "a packing the oracle refuses passed the plausibility check", *oracle);
  return 0;
}
