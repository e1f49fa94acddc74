// Fuzz target: config.json, the run configuration reader (core/run_config.hpp): JSON into a
// core::RunConfig, its validation, and the round trip of what it accepts.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/json_input.hpp"
#include "core/run_config.hpp"
#include "fuzz/fuzz_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace confpack;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  core::RunConfig cfg;
  try {
    core::from_json(core::parseJsonText(text, "config.json"), cfg);
    cfg.validate();
  } catch (const std::invalid_argument& e) {
    fuzz::checkRefusal(e);
    return 0;
  }
  // The configuration a run writes back reads back to the same configuration.
  nlohmann::json written;
  core::to_json(written, cfg);
  core::RunConfig back;
  core::from_json(written, back);
  nlohmann::json again;
  core::to_json(again, back);
  fuzz::require(again == written, "config.json read back differs from the one written", written.dump());
  back.validate();
  return 0;
}
