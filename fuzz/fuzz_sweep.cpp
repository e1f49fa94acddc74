// Fuzz target: the sweep file reader (study/sweep.hpp): parsing, the expansion into the run table
// and its listing (`confpack sweep FILE --list`), equal_time's partners.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/json_input.hpp"
#include "fuzz/fuzz_checks.hpp"
#include "study/sweep.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace confpack;
  constexpr std::string_view source = "sweep.json";
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // A few hundred runs at most: the limit is what is exercised, and a table of 100,000 runs (the
  // default limit) would take seconds per input.
  constexpr std::size_t kMaxRuns = 256;
  study::SweepSpec spec;
  try {
    spec = study::parseSweepSpec(core::parseJsonText(text, source), source, kMaxRuns);
  } catch (const std::invalid_argument& e) {
    fuzz::checkRefusal(e, source);
    return 0;
  }
  std::vector<study::SweepRun> runs;
  try {
    runs = study::expandRuns(spec);
  } catch (const std::invalid_argument& e) {
    fuzz::checkRefusal(e);
    return 0;
  }
  // Every run has its own name, and runs sharing a deposit differ only after the deposition.
  for (std::size_t i = 0; i < runs.size(); ++i) {
    fuzz::require(runs[i].index == i, "run indices are not the table order");
    if (i > 0) fuzz::require(runs[i].name > runs[i - 1].name, "run names are not increasing");
  }
  // equal_time's partners: refused by name, or each an nscd run of the same deposit.
  try {
    const auto partners = study::equalTimePartners(runs, spec.equalTime);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      if (!partners[i]) continue;
      const study::SweepRun& p = runs.at(*partners[i]);
      fuzz::require(p.config.backend == spec.equalTime && p.depositIndex == runs[i].depositIndex,
                    "an equal_time partner of another backend or deposit");
    }
  } catch (const std::invalid_argument& e) {
    fuzz::checkRefusal(e);
  }
  (void)study::formatRunTable(runs);
  return 0;
}
