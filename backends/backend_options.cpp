// The backends' settings by name, apart from backend_factory.cpp's construction: what checks or
// lists a backend's options needs their settings tables only, not the backends (the fuzz targets
// of the readers link this file alone).
#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "backends/backend_factory.hpp"
#include "backends/bullet/bullet_settings.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "core/json_input.hpp"

namespace confpack::backends {

namespace {

/// A key of the other backend's table and not of `name`'s: what a run's config.json (which lists
/// every setting of its backend) holds after its "backend" was changed by hand. Named as such,
/// since the unknown-key message lists only the right keys.
void refuseOtherBackendsKey(std::string_view name, const nlohmann::json& options) {
  if (!options.is_object()) return;
  const bool nscd = name == "nscd";
  for (const auto& item : options.items()) {
    const std::string& key = item.key();
    const bool own = nscd ? nscd::settingsTable().has(key) : bullet::settingsTable().has(key);
    const bool other = nscd ? bullet::settingsTable().has(key) : nscd::settingsTable().has(key);
    if (!own && other)
      throw std::invalid_argument(
          fmt::format("{}.{}: a setting of {}, not of {} (backend_options holds the run's backend's settings only: "
                      "drop it when changing a config.json's backend)",
                      name, key, nscd ? "bullet" : "nscd", name));
  }
}

}  // namespace

void checkBackendOptions(std::string_view name, const nlohmann::json& options) {
  if (name == "nscd" || name == "bullet") refuseOtherBackendsKey(name, options);
  if (name == "nscd") {
    nscd::settingsFromJson(options);
  } else if (name == "bullet") {
    bullet::bulletSettingsFromJson(options);
  } else {
    throw std::invalid_argument(fmt::format("unknown backend '{}' (expected nscd or bullet)", core::textExcerpt(name, 40)));
  }
}

std::string optionsMarkdown(std::string_view name) {
  if (name == "nscd") return nscd::settingsTable().markdown(nscd::NscdSettings{});
  if (name == "bullet") return bullet::settingsTable().markdown(bullet::BulletSettings{});
  throw std::invalid_argument(fmt::format("unknown backend '{}' (expected nscd or bullet)", core::textExcerpt(name, 40)));
}

}  // namespace confpack::backends
