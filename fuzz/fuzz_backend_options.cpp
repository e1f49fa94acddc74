// Fuzz target: --backend-options, read by both backends' settings tables
// (backends/nscd/nscd_settings.hpp, backends/bullet/bullet_settings.hpp), as
// backends::checkBackendOptions does before a run; and the round trip of what they accept
// (result.json records the resolved set).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "backends/bullet/bullet_settings.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "core/json_input.hpp"
#include "fuzz/fuzz_checks.hpp"

namespace {

template <class Settings, class Read>
void readBack(const nlohmann::json& options, Read read) {
  Settings s;
  try {
    s = read(options);
  } catch (const std::invalid_argument& e) {
    confpack::fuzz::checkRefusal(e);
    return;
  }
  const nlohmann::json written = s;
  const nlohmann::json again = read(written);
  confpack::fuzz::require(again == written, "backend options read back differ from the ones written", written.dump());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace confpack;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  nlohmann::json options;
  try {
    options = core::parseJsonText(text, "--backend-options");
  } catch (const std::invalid_argument& e) {
    fuzz::checkRefusal(e, "--backend-options");
    return 0;
  }
  readBack<nscd::NscdSettings>(options, [](const nlohmann::json& j) { return nscd::settingsFromJson(j); });
  readBack<bullet::BulletSettings>(options, [](const nlohmann::json& j) { return bullet::bulletSettingsFromJson(j); });
  return 0;
}
