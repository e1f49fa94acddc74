// The backends' settings by name, apart from backend_factory.cpp's construction: what checks or
// lists a backend's options needs their settings tables only, not the backends (the fuzz targets
// of the readers link this file alone).
#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "backends/backend_factory.hpp"
#include "backends/bullet/bullet_settings.hpp"
#include "backends/nscd/nscd_settings.hpp"

namespace confpack::backends {

namespace {

/// Refuses a key of the other backend's table that is not one of `own`'s: what a run's
/// config.json (which lists every setting of its backend) holds after its "backend" was changed
/// by hand. Named as such, since the unknown-key message lists only the right keys.
template <class Own, class Other>
void refuseOtherBackendsKeys(std::string_view name, const Own& own, std::string_view otherName, const Other& other,
                             const nlohmann::json& options) {
  if (!options.is_object()) return;
  for (const auto& item : options.items())
    if (!own.has(item.key()) && other.has(item.key()))
      throw std::invalid_argument(
          fmt::format("{}.{}: a setting of {}, not of {} (backend_options holds the run's backend's settings only: "
                      "drop it when changing a config.json's backend)",
                      name, item.key(), otherName, name));
}

}  // namespace

void checkBackendOptions(std::string_view name, const nlohmann::json& options) {
  if (name == "nscd") {
    refuseOtherBackendsKeys(name, nscd::settingsTable(), "bullet", bullet::settingsTable(), options);
    nscd::settingsFromJson(options);
  } else if (name == "bullet") {
    refuseOtherBackendsKeys(name, bullet::settingsTable(), "nscd", nscd::settingsTable(), options);
    bullet::bulletSettingsFromJson(options);
  } else {
    throw std::invalid_argument(core::unknownBackendMessage(name));
  }
}

std::string optionsMarkdown(std::string_view name) {
  if (name == "nscd") return nscd::settingsTable().markdown(nscd::NscdSettings{});
  if (name == "bullet") return bullet::settingsTable().markdown(bullet::BulletSettings{});
  throw std::invalid_argument(core::unknownBackendMessage(name));
}

}  // namespace confpack::backends
