#pragma once
#include <memory>
#include <nlohmann/json.hpp>

#include "core/backend.hpp"

namespace confpack::nscd {

/// The native Moreau-Jean / nonlinear Gauss-Seidel backend (SPEC 5.1).
std::unique_ptr<core::ContactBackend> makeNscdBackend(const core::SystemDef& system, const nlohmann::json& options);

}  // namespace confpack::nscd
