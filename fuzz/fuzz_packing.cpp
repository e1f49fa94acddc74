// Fuzz target: the packing file reader (core/packing_io.hpp) and the plausibility check that
// analyze and run --from apply to what it accepts (analysis/plausibility.hpp).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "analysis/plausibility.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "fuzz/fuzz_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace confpack;
  constexpr std::string_view source = "packing.json";
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  core::Packing packing;
  try {
    packing = core::packingFromJson(core::parseJsonText(text, source), source);
  } catch (const std::invalid_argument& e) {
    fuzz::checkRefusal(e, source);
    return 0;
  }
  // Written as a file and read back, an accepted packing gives the same document
  // (docs/packing-format.md: "reading it back gives the same bits").
  const nlohmann::json written = core::toJson(packing);
  const core::Packing back = core::packingFromJson(written, "written");
  fuzz::require(core::toJson(back) == written, "a packing read back differs from the one written");
  // The plausibility check refuses what the analysis cannot take (a packing mixing spheres and
  // pinacoids; the commands refuse those before it, analysis::checkPlausible) with invalid_argument.
  try {
    (void)analysis::implausibility(packing);
  } catch (const std::invalid_argument& e) {
    fuzz::checkRefusal(e);
  }
  return 0;
}
