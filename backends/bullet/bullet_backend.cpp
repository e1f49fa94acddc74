#include "backends/bullet/bullet_backend.hpp"

#include <stdexcept>

namespace confpack::bullet {
// Temporary until the bullet issue lands: refuse clearly rather than pretend.
std::unique_ptr<core::ContactBackend> makeBulletBackend(const core::SystemDef&, const nlohmann::json&) {
  throw std::invalid_argument("backend 'bullet' is not built yet");
}
}  // namespace confpack::bullet
