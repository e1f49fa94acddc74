#pragma once
#include <memory>
#include <nlohmann/json.hpp>

#include "core/backend.hpp"

namespace confpack::nscd {

/// The native Moreau-Jean contact dynamics backend (docs/model.md, "nscd: Moreau-Jean contact
/// dynamics").
std::unique_ptr<core::ContactBackend> makeNscdBackend(const core::SystemDef& system, const nlohmann::json& options);

}  // namespace confpack::nscd
