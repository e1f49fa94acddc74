#include "backends/backend_factory.hpp"

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace confpack::backends {

const std::vector<std::string_view>& backendNames() {
  static const std::vector<std::string_view> names = {"nscd", "bullet"};
  return names;
}

std::unique_ptr<core::ContactBackend> makeBackend(std::string_view name, const core::SystemDef& system,
                                                  const nlohmann::json& options) {
  (void)system;
  (void)options;
  // Filled in by the backend issues: nscd::makeNscdBackend, bullet::makeBulletBackend.
  throw std::invalid_argument(fmt::format("backend '{}' is not available yet in this build", name));
}

}  // namespace confpack::backends
