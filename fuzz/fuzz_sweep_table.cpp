// Fuzz target: the sweep table, SWEEPDIR/sweep.json (study/sweep.hpp, parseRunTable), which
// `confpack report` reads and a user may edit: the sweep file it holds, each run's name, deposit
// and configuration, and the round trip of what it accepts.
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/json_input.hpp"
#include "fuzz/fuzz_checks.hpp"
#include "study/sweep.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace confpack;
  constexpr std::string_view source = "sweep.json";
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  study::SweepSpec spec;
  std::vector<study::SweepRun> runs;
  try {
    runs = study::parseRunTable(core::parseJsonText(text, source), source, &spec);
  } catch (const std::invalid_argument& e) {
    fuzz::checkRefusal(e, source);
    return 0;
  }
  // What the report relies on: runs in table order, each name one folder of runs/ used once, each
  // deposit one of the table's.
  std::set<std::string> names;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    fuzz::require(runs[i].index == i, "run indices are not the table order");
    const std::string& name = runs[i].name;
    fuzz::require(!name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos,
                  "a run name is not a folder name", name);
    fuzz::require(names.insert(name).second, "two runs share a name", name);
    fuzz::require(runs[i].depositIndex < runs.size(), "a deposit index beyond the table");
  }
  // The table written back (what prepareSweepDir writes) reads back to the same table.
  const nlohmann::json written = study::runTableDocument(spec, runs);
  study::SweepSpec specAgain;
  const std::vector<study::SweepRun> again = study::parseRunTable(written, source, &specAgain);
  fuzz::require(study::runTableDocument(specAgain, again) == written,
                "sweep.json read back differs from the one written", written.dump().substr(0, 2000));
  (void)study::formatRunTable(runs);
  return 0;
}
