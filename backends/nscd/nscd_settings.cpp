#include "backends/nscd/nscd_settings.hpp"

#include <fmt/format.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace confpack::nscd {

void NscdSettings::validate() const {
  auto bad = [](const char* key, const std::string& what) {
    throw std::invalid_argument(fmt::format("nscd option '{}' {}", key, what));
  };
  if (!(theta >= 0.5 && theta <= 1.0)) bad("theta", fmt::format("must be in [0.5, 1] (got {})", theta));
  if (!(tolerance > 0.0) || !std::isfinite(tolerance))
    bad("tolerance", fmt::format("must be a positive number (got {})", tolerance));
  if (maxIterations < 1) bad("max_iterations", fmt::format("must be >= 1 (got {})", maxIterations));
  if (minIterations < 1 || minIterations > maxIterations)
    bad("min_iterations", fmt::format("must be in [1, max_iterations] (got {})", minIterations));
  if (!(relaxation > 0.0 && relaxation < 2.0))
    bad("relaxation", fmt::format("must be in (0, 2) (got {})", relaxation));
  if (!(alertDistance >= 0.0) || !std::isfinite(alertDistance))
    bad("alert_distance", fmt::format("must be >= 0 (got {})", alertDistance));
  if (!(gapCorrection > 0.0 && gapCorrection <= 1.0))
    bad("gap_correction", fmt::format("must be in (0, 1] (got {})", gapCorrection));
  if (!(maxCorrectionVelocity > 0.0) || !std::isfinite(maxCorrectionVelocity))
    bad("max_correction_velocity", fmt::format("must be a positive number (got {})", maxCorrectionVelocity));
  if (!(damping >= 0.0) || !std::isfinite(damping))
    bad("damping", fmt::format("must be a number >= 0 (got {})", damping));
  if (!(dampingSpeed > 0.0)) bad("damping_speed", fmt::format("must be > 0 (got {})", dampingSpeed));
  if (threads < 1) bad("threads", fmt::format("must be >= 1 (got {})", threads));
}

std::string toString(SolverKind k) { return k == SolverKind::Mprgp ? "mprgp" : "nlgs"; }
std::string toString(ExpansionKind k) { return k == ExpansionKind::ProjectedCg ? "projected_cg" : "gradient"; }
std::string toString(PreconditionerKind k) { return k == PreconditionerKind::SymmetricGaussSeidel ? "sgs" : "none"; }

void to_json(nlohmann::json& j, const NscdSettings& s) {
  j = {{"theta", s.theta},
       {"solver", toString(s.solver)},
       {"expansion", toString(s.expansion)},
       {"preconditioner", toString(s.preconditioner)},
       {"tolerance", s.tolerance},
       {"max_iterations", s.maxIterations},
       {"min_iterations", s.minIterations},
       {"relaxation", s.relaxation},
       {"alert_distance", s.alertDistance},
       {"gap_correction", s.gapCorrection},
       {"max_correction_velocity", s.maxCorrectionVelocity},
       {"damping", s.damping},
       {"damping_speed", std::isfinite(s.dampingSpeed) ? nlohmann::json(s.dampingSpeed) : nlohmann::json(nullptr)},
       {"threads", s.threads}};
}

namespace {

/// Sets `field` to the choice named by `value`, or refuses it with the key and the names allowed.
template <class Kind>
void readChoice(const std::string& key, const nlohmann::json& value, Kind& field,
                std::initializer_list<std::pair<const char*, Kind>> choices) {
  std::string allowed;
  for (const auto& [name, kind] : choices) {
    if (value == name) {
      field = kind;
      return;
    }
    allowed += fmt::format("{}\"{}\"", allowed.empty() ? "" : " or ", name);
  }
  throw std::invalid_argument(fmt::format("nscd option '{}' must be {} (got {})", key, allowed, value.dump()));
}

}  // namespace

NscdSettings defaultsFor(SolverKind kind) {
  NscdSettings s;
  s.solver = kind;
  if (kind == SolverKind::Nlgs) {
    s.tolerance = 1e-6;
    s.maxIterations = 2000;
  }
  return s;
}

NscdSettings settingsFromJson(const nlohmann::json& j) {
  NscdSettings s;
  if (j.is_null()) return s;
  if (!j.is_object()) throw std::invalid_argument("nscd options must be a JSON object");
  // The solver first: it sets the defaults of the keys that depend on it.
  if (const auto it = j.find("solver"); it != j.end()) {
    SolverKind kind = SolverKind::Mprgp;
    readChoice("solver", *it, kind, {{"nlgs", SolverKind::Nlgs}, {"mprgp", SolverKind::Mprgp}});
    s = defaultsFor(kind);
  }
  for (const auto& [key, value] : j.items()) {
    auto number = [&](double& field) {
      if (!value.is_number()) throw std::invalid_argument(fmt::format("nscd option '{}' must be a number", key));
      field = value.get<double>();
    };
    auto integer = [&](int& field) {
      if (!value.is_number_integer())
        throw std::invalid_argument(fmt::format("nscd option '{}' must be an integer", key));
      field = value.get<int>();
    };
    if (key == "theta") number(s.theta);
    else if (key == "solver") continue;  // read above
    else if (key == "expansion")
      readChoice(key, value, s.expansion,
                 {{"projected_cg", ExpansionKind::ProjectedCg}, {"gradient", ExpansionKind::Gradient}});
    else if (key == "preconditioner")
      readChoice(key, value, s.preconditioner,
                 {{"sgs", PreconditionerKind::SymmetricGaussSeidel}, {"none", PreconditionerKind::None}});
    else if (key == "tolerance") number(s.tolerance);
    else if (key == "max_iterations") integer(s.maxIterations);
    else if (key == "min_iterations") integer(s.minIterations);
    else if (key == "relaxation") number(s.relaxation);
    else if (key == "alert_distance") number(s.alertDistance);
    else if (key == "gap_correction") number(s.gapCorrection);
    else if (key == "max_correction_velocity") number(s.maxCorrectionVelocity);
    else if (key == "damping") number(s.damping);
    else if (key == "damping_speed") {
      if (value.is_null()) s.dampingSpeed = std::numeric_limits<double>::infinity();  // no limit
      else number(s.dampingSpeed);
    }
    else if (key == "threads") integer(s.threads);
    else
      throw std::invalid_argument(fmt::format(
          "unknown nscd option '{}' (known: theta, solver, expansion, preconditioner, tolerance, max_iterations, min_iterations, relaxation, alert_distance, "
          "gap_correction, max_correction_velocity, damping, damping_speed, threads)",
          key));
  }
  s.validate();
  return s;
}

}  // namespace confpack::nscd
