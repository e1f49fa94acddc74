#pragma once
// No Bullet header here: the implementation is a pimpl in bullet_backend.cpp so that
// BT_USE_DOUBLE_PRECISION never reaches the rest of the code.
#include <memory>
#include <nlohmann/json.hpp>

#include "core/backend.hpp"

namespace confpack::bullet {

/// Bullet's sequential-impulse solver behind the backend interface (SPEC 5.2).
std::unique_ptr<core::ContactBackend> makeBulletBackend(const core::SystemDef& system, const nlohmann::json& options);

}  // namespace confpack::bullet
