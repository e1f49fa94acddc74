#include "backends/backend_factory.hpp"

#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "backends/bullet/bullet_backend.hpp"
#include "backends/nscd/nscd_backend.hpp"

namespace confpack::backends {

const std::vector<std::string_view>& backendNames() {
  static const std::vector<std::string_view> names(core::kBackendNames.begin(), core::kBackendNames.end());
  return names;
}

std::unique_ptr<core::ContactBackend> makeBackend(std::string_view name, const core::SystemDef& system,
                                                  const nlohmann::json& options) {
  if (name == "nscd") return nscd::makeNscdBackend(system, options);
  if (name == "bullet") return bullet::makeBulletBackend(system, options);
  throw std::invalid_argument(core::unknownBackendMessage(name));
}

}  // namespace confpack::backends
