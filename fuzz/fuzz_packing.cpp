// Fuzz target: the packing file reader (core/packing_io.hpp) and the plausibility check that
// analyze and run --from apply to what it accepts (analysis/plausibility.hpp).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "analysis/plausibility.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_packing_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace confpack;
  const std::optional<core::Packing> accepted = fuzz::acceptedPacking(data, size);
  if (!accepted) return 0;
  const core::Packing& packing = *accepted;
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
