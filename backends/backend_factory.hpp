#pragma once
// The one place that knows the backends exist.
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/backend.hpp"

namespace confpack::backends {

/// Names accepted by makeBackend, in a stable order: {"nscd", "bullet"}.
const std::vector<std::string_view>& backendNames();

/// Builds a backend by name. `options` holds backend-specific settings (documented by each
/// backend; unknown keys are refused); missing keys take their defaults.
/// Throws std::invalid_argument for an unknown name or a bad option.
std::unique_ptr<core::ContactBackend> makeBackend(std::string_view name, const core::SystemDef& system,
                                                  const nlohmann::json& options = nlohmann::json::object());

/// Checks `options` as makeBackend would, without a system: a command can then refuse an unknown
/// key or an out-of-range value as bad input, before any work. Throws std::invalid_argument.
void checkBackendOptions(std::string_view name, const nlohmann::json& options);

/// The backend's options as a Markdown table (key, default, unit, accepted values, meaning), from
/// the same description that reads them. Throws std::invalid_argument for an unknown name.
std::string optionsMarkdown(std::string_view name);

}  // namespace confpack::backends
