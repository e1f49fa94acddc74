#include "backends/bullet/bullet_settings.hpp"

#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>

namespace confpack::bullet {

void BulletSettings::validate() const {
  auto bad = [](const char* key, const std::string& what) {
    throw std::invalid_argument(fmt::format("bullet option '{}' {}", key, what));
  };
  auto finite = [](double v) { return std::isfinite(v); };
  if (iterations < 1) bad("iterations", fmt::format("must be >= 1 (got {})", iterations));
  if (!(residualThreshold >= 0.0) || !finite(residualThreshold))
    bad("residual_threshold", fmt::format("must be >= 0 (got {})", residualThreshold));
  if (!(splitImpulsePenetrationThreshold <= 0.0) || !finite(splitImpulsePenetrationThreshold))
    bad("split_impulse_penetration_threshold", fmt::format("must be <= 0 (got {})", splitImpulsePenetrationThreshold));
  if (!(splitImpulseTurnErp >= 0.0 && splitImpulseTurnErp <= 1.0))
    bad("split_impulse_turn_erp", fmt::format("must be in [0, 1] (got {})", splitImpulseTurnErp));
  if (!(erp >= 0.0 && erp <= 1.0)) bad("erp", fmt::format("must be in [0, 1] (got {})", erp));
  if (!(erp2 >= 0.0 && erp2 <= 1.0)) bad("erp2", fmt::format("must be in [0, 1] (got {})", erp2));
  if (!(globalCfm >= 0.0) || !finite(globalCfm)) bad("global_cfm", fmt::format("must be >= 0 (got {})", globalCfm));
  if (!(sor > 0.0 && sor < 2.0)) bad("sor", fmt::format("must be in (0, 2) (got {})", sor));
  if (!(linearSlop >= 0.0) || !finite(linearSlop)) bad("linear_slop", fmt::format("must be >= 0 (got {})", linearSlop));
  if (!(warmStartingFactor >= 0.0 && warmStartingFactor <= 1.0))
    bad("warm_starting_factor", fmt::format("must be in [0, 1] (got {})", warmStartingFactor));
  if (!(contactBreakingThreshold > 0.0) || !finite(contactBreakingThreshold))
    bad("contact_breaking_threshold", fmt::format("must be a positive number (got {})", contactBreakingThreshold));
  if (frictionDirections != 1 && frictionDirections != 2)
    bad("friction_directions", fmt::format("must be 1 or 2 (got {})", frictionDirections));
  if (planePerturbationIterations < 0)
    bad("plane_perturbation_iterations", fmt::format("must be >= 0 (got {})", planePerturbationIterations));
  if (planePerturbationMinPoints < 0)
    bad("plane_perturbation_min_points", fmt::format("must be >= 0 (got {})", planePerturbationMinPoints));
  if (manifoldsPerGrain < 1) bad("manifolds_per_grain", fmt::format("must be >= 1 (got {})", manifoldsPerGrain));
  if (threads < 1) bad("threads", fmt::format("must be >= 1 (got {})", threads));
}

void to_json(nlohmann::json& j, const BulletSettings& s) {
  j = {{"iterations", s.iterations},
       {"residual_threshold", s.residualThreshold},
       {"split_impulse", s.splitImpulse},
       {"split_impulse_penetration_threshold", s.splitImpulsePenetrationThreshold},
       {"split_impulse_turn_erp", s.splitImpulseTurnErp},
       {"erp", s.erp},
       {"erp2", s.erp2},
       {"global_cfm", s.globalCfm},
       {"sor", s.sor},
       {"linear_slop", s.linearSlop},
       {"warm_starting_factor", s.warmStartingFactor},
       {"contact_breaking_threshold", s.contactBreakingThreshold},
       {"friction_directions", s.frictionDirections},
       {"skip_zero_friction_rows", s.skipZeroFrictionRows},
       {"sat_convex", s.satConvex},
       {"plane_perturbation_iterations", s.planePerturbationIterations},
       {"plane_perturbation_min_points", s.planePerturbationMinPoints},
       {"randomize_order", s.randomizeOrder},
       {"manifolds_per_grain", s.manifoldsPerGrain},
       {"threads", s.threads}};
}

BulletSettings bulletSettingsFromJson(const nlohmann::json& j) {
  BulletSettings s;
  if (j.is_null()) return s;
  if (!j.is_object()) throw std::invalid_argument("bullet options must be a JSON object");
  // One reader per key; the table doubles as the list of known keys in the error message.
  using Reader = std::function<void(const std::string&, const nlohmann::json&)>;
  auto number = [](double& field) -> Reader {
    return [&field](const std::string& key, const nlohmann::json& v) {
      if (!v.is_number()) throw std::invalid_argument(fmt::format("bullet option '{}' must be a number", key));
      field = v.get<double>();
    };
  };
  auto integer = [](int& field) -> Reader {
    return [&field](const std::string& key, const nlohmann::json& v) {
      if (!v.is_number_integer())
        throw std::invalid_argument(fmt::format("bullet option '{}' must be an integer", key));
      field = v.get<int>();
    };
  };
  auto boolean = [](bool& field) -> Reader {
    return [&field](const std::string& key, const nlohmann::json& v) {
      if (!v.is_boolean()) throw std::invalid_argument(fmt::format("bullet option '{}' must be true or false", key));
      field = v.get<bool>();
    };
  };
  const std::map<std::string, Reader> readers = {
      {"iterations", integer(s.iterations)},
      {"residual_threshold", number(s.residualThreshold)},
      {"split_impulse", boolean(s.splitImpulse)},
      {"split_impulse_penetration_threshold", number(s.splitImpulsePenetrationThreshold)},
      {"split_impulse_turn_erp", number(s.splitImpulseTurnErp)},
      {"erp", number(s.erp)},
      {"erp2", number(s.erp2)},
      {"global_cfm", number(s.globalCfm)},
      {"sor", number(s.sor)},
      {"linear_slop", number(s.linearSlop)},
      {"warm_starting_factor", number(s.warmStartingFactor)},
      {"contact_breaking_threshold", number(s.contactBreakingThreshold)},
      {"friction_directions", integer(s.frictionDirections)},
      {"skip_zero_friction_rows", boolean(s.skipZeroFrictionRows)},
      {"sat_convex", boolean(s.satConvex)},
      {"plane_perturbation_iterations", integer(s.planePerturbationIterations)},
      {"plane_perturbation_min_points", integer(s.planePerturbationMinPoints)},
      {"randomize_order", boolean(s.randomizeOrder)},
      {"manifolds_per_grain", integer(s.manifoldsPerGrain)},
      {"threads", integer(s.threads)},
  };
  for (const auto& [key, value] : j.items()) {
    auto it = readers.find(key);
    if (it == readers.end()) {
      std::string known;
      for (const auto& [k, r] : readers) known += (known.empty() ? "" : ", ") + k;
      throw std::invalid_argument(fmt::format("unknown bullet option '{}' (known: {})", key, known));
    }
    it->second(key, value);
  }
  s.validate();
  return s;
}

}  // namespace confpack::bullet
