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

void checkBackendOptions(std::string_view name, const nlohmann::json& options) {
  if (name == "nscd") {
    nscd::settingsFromJson(options);
  } else if (name == "bullet") {
    bullet::bulletSettingsFromJson(options);
  } else {
    throw std::invalid_argument(fmt::format("unknown backend '{}' (expected nscd or bullet)", name));
  }
}

std::string optionsMarkdown(std::string_view name) {
  if (name == "nscd") return nscd::settingsTable().markdown(nscd::NscdSettings{});
  if (name == "bullet") return bullet::settingsTable().markdown(bullet::BulletSettings{});
  throw std::invalid_argument(fmt::format("unknown backend '{}' (expected nscd or bullet)", name));
}

}  // namespace confpack::backends
