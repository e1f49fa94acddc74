#include "core/run_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string_view>

namespace confpack::core {

namespace {

using nlohmann::json;

/// A configuration file is written by us or edited by a user: refuse a misspelt key rather than
/// silently run with its default.
void onlyKeys(const json& j, std::string_view where, std::initializer_list<std::string_view> allowed) {
  if (!j.is_object())
    throw std::invalid_argument(fmt::format("{}: must be a JSON object (got {})", where, j.type_name()));
  for (const auto& [key, value] : j.items()) {
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::string list;
      for (auto a : allowed) list += fmt::format("{}{}", list.empty() ? "" : ", ", a);
      throw std::invalid_argument(fmt::format("{}.{}: unknown key (allowed: {})", where, key, list));
    }
  }
}

/// j.value(key, fallback) with the key named in the error when the type is wrong (nlohmann's own
/// message does not say which key).
template <class T>
T valueOr(const json& j, std::string_view where, const char* key, const T& fallback) {
  if (!j.contains(key)) return fallback;
  try {
    return j.at(key).get<T>();
  } catch (const json::exception&) {
    throw std::invalid_argument(fmt::format("{}.{}: wrong type ({})", where, key, j.at(key).dump()));
  }
}

// Names accepted by backends::makeBackend. core cannot see backends/ (it sits below them in the
// dependency graph), so the list is repeated here; tests/apps/test_cli.cpp checks the two agree.
constexpr std::string_view kBackendNames[] = {"nscd", "bullet"};

}  // namespace

std::string toString(Protocol p) { return p == Protocol::QuasiStatic ? "quasi-static" : "dynamic"; }

void to_json(json& j, const CompactionDef& c) {
  j = {{"dt", c.dt},
       {"adaptive_dt", c.adaptiveDt},
       {"time_limit", c.timeLimit},
       {"check_interval", c.checkInterval},
       {"frame_interval", c.frameInterval},
       {"force_ratio", c.forceRatio},
       {"moment_ratio", c.momentRatio},
       {"kinetic_ratio", c.kineticRatio},
       {"protocol", toString(c.protocol)},
       {"switch_kinetic_ratio", c.switchKineticRatio},
       {"trust_radius", c.trustRadius},
       {"settle_tolerance", c.settleTolerance},
       {"finisher_max_step", c.finisherMaxStep},
       {"finisher_max_steps", c.finisherMaxSteps}};
}

void from_json(const json& j, CompactionDef& c) {
  constexpr std::string_view w = "compaction";
  onlyKeys(j, w,
           {"dt", "adaptive_dt", "time_limit", "check_interval", "frame_interval", "force_ratio", "moment_ratio",
            "kinetic_ratio", "protocol", "switch_kinetic_ratio", "trust_radius", "settle_tolerance",
            "finisher_max_step", "finisher_max_steps"});
  const CompactionDef d;
  c.dt = valueOr(j, w, "dt", d.dt);
  c.adaptiveDt = valueOr(j, w, "adaptive_dt", d.adaptiveDt);
  c.timeLimit = valueOr(j, w, "time_limit", d.timeLimit);
  c.checkInterval = valueOr(j, w, "check_interval", d.checkInterval);
  c.frameInterval = valueOr(j, w, "frame_interval", d.frameInterval);
  c.forceRatio = valueOr(j, w, "force_ratio", d.forceRatio);
  c.momentRatio = valueOr(j, w, "moment_ratio", d.momentRatio);
  c.kineticRatio = valueOr(j, w, "kinetic_ratio", d.kineticRatio);
  const std::string protocol = valueOr(j, w, "protocol", toString(d.protocol));
  if (protocol == "dynamic")
    c.protocol = Protocol::Dynamic;
  else if (protocol == "quasi-static")
    c.protocol = Protocol::QuasiStatic;
  else
    throw std::invalid_argument(
        fmt::format("{}.protocol: unknown protocol '{}' (expected dynamic or quasi-static)", w, protocol));
  c.switchKineticRatio = valueOr(j, w, "switch_kinetic_ratio", d.switchKineticRatio);
  c.trustRadius = valueOr(j, w, "trust_radius", d.trustRadius);
  c.settleTolerance = valueOr(j, w, "settle_tolerance", d.settleTolerance);
  c.finisherMaxStep = valueOr(j, w, "finisher_max_step", d.finisherMaxStep);
  c.finisherMaxSteps = valueOr(j, w, "finisher_max_steps", d.finisherMaxSteps);
}

void to_json(json& j, const RunConfig& c) {
  j = {{"box", c.box},
       {"population", c.population},
       {"deposition", c.deposition},
       {"compaction", c.compaction},
       {"backend", c.backend},
       {"backend_options", c.backendOptions},
       {"seed", c.seed},
       {"threads", c.threads}};
}

void from_json(const json& j, RunConfig& c) {
  constexpr std::string_view w = "config";
  onlyKeys(j, w, {"box", "population", "deposition", "compaction", "backend", "backend_options", "seed", "threads"});
  const RunConfig d;
  // The nested definitions own their keys; wrap their nlohmann type errors so the message says
  // which section was wrong.
  auto section = [&](const char* key, auto& out) {
    if (!j.contains(key)) return;
    try {
      j.at(key).get_to(out);
    } catch (const json::exception& e) {
      throw std::invalid_argument(fmt::format("{}.{}: {}", w, key, e.what()));
    }
  };
  c.box = d.box;
  c.population = d.population;
  c.deposition = d.deposition;
  c.compaction = d.compaction;
  section("box", c.box);
  section("population", c.population);
  section("deposition", c.deposition);
  section("compaction", c.compaction);
  c.backend = valueOr(j, w, "backend", d.backend);
  c.backendOptions = j.contains("backend_options") ? j.at("backend_options") : d.backendOptions;
  if (j.contains("seed") && !j.at("seed").is_number_unsigned())
    throw std::invalid_argument(fmt::format("{}.seed: must be an integer >= 0 (got {})", w, j.at("seed").dump()));
  c.seed = valueOr(j, w, "seed", d.seed);
  if (j.contains("threads") && !j.at("threads").is_number_integer())
    throw std::invalid_argument(fmt::format("{}.threads: must be an integer (got {})", w, j.at("threads").dump()));
  c.threads = valueOr(j, w, "threads", d.threads);
}

void RunConfig::validate() const {
  box.validate();
  population.validate();
  if (std::find(std::begin(kBackendNames), std::end(kBackendNames), backend) == std::end(kBackendNames))
    throw std::invalid_argument(fmt::format("backend: unknown backend '{}' (expected nscd or bullet)", backend));
  if (!backendOptions.is_object())
    throw std::invalid_argument(fmt::format("backend_options: must be a JSON object (got {})", backendOptions.dump()));
  if (threads < 1) throw std::invalid_argument(fmt::format("threads: must be >= 1 (got {})", threads));
  if (!(deposition.expectedSolidFraction > 0.0 && deposition.expectedSolidFraction < 1.0))
    throw std::invalid_argument(fmt::format("deposition: expected solid fraction must be in (0, 1) (got {})",
                                            deposition.expectedSolidFraction));
  const CompactionDef& k = compaction;
  if (!(k.dt >= 0.0) || !std::isfinite(k.dt))
    throw std::invalid_argument(fmt::format("compaction.dt: must be >= 0, 0 meaning automatic (got {})", k.dt));
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::invalid_argument(fmt::format("compaction.{}: must be a positive number (got {})", name, v));
  };
  positive(k.timeLimit, "time_limit");
  if (k.timeLimit > kMaxTimeLimit)
    throw std::invalid_argument(fmt::format("compaction.time_limit: must be at most {:g} t0 (got {:g})", kMaxTimeLimit,
                                            k.timeLimit));
  positive(k.forceRatio, "force_ratio");
  positive(k.momentRatio, "moment_ratio");
  positive(k.kineticRatio, "kinetic_ratio");
  positive(k.switchKineticRatio, "switch_kinetic_ratio");
  positive(k.trustRadius, "trust_radius");
  positive(k.settleTolerance, "settle_tolerance");
  positive(k.finisherMaxStep, "finisher_max_step");
  if (k.trustRadius > 0.5)
    throw std::invalid_argument(
        fmt::format("compaction.trust_radius: must be at most 0.5 of the smallest grain (got {})", k.trustRadius));
  if (k.finisherMaxSteps < 1)
    throw std::invalid_argument(
        fmt::format("compaction.finisher_max_steps: must be >= 1 (got {})", k.finisherMaxSteps));
  if (k.checkInterval < 1)
    throw std::invalid_argument(fmt::format("compaction.check_interval: must be >= 1 (got {})", k.checkInterval));
  if (k.frameInterval < 0)
    throw std::invalid_argument(fmt::format("compaction.frame_interval: must be >= 0 (got {})", k.frameInterval));
}

}  // namespace confpack::core
