#include "core/run_config.hpp"

#include "core/backend.hpp"
#include "core/json_input.hpp"
#include "core/settings_table.hpp"

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
      throw std::invalid_argument(fmt::format("{}.{}: unknown key (allowed: {})", where, textExcerpt(key), list));
    }
  }
}

/// The keys of a section read with j.value() (box, population and its pinacoid) against those of
/// its defaults (`known`, as JSON): those readers take a misspelt key's default without a word.
void knownKeysOnly(const json& j, const json& known, const std::string& where) {
  if (!j.is_object()) return;  // the section's own reader refuses it
  for (const auto& [key, value] : j.items()) {
    if (!known.contains(key)) {
      std::string list;
      for (const auto& [k, v] : known.items()) list += fmt::format("{}{}", list.empty() ? "" : ", ", k);
      throw std::invalid_argument(fmt::format("{}.{}: unknown key (allowed: {})", where, textExcerpt(key), list));
    }
    if (value.is_object() && known.at(key).is_object()) knownKeysOnly(value, known.at(key), where + "." + key);
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
    throw std::invalid_argument(fmt::format("{}.{}: wrong type ({})", where, key, jsonExcerpt(j.at(key))));
  }
}

}  // namespace

std::string toString(Protocol p) { return p == Protocol::QuasiStatic ? "quasi-static" : "dynamic"; }

const SettingsTable<CompactionDef>& compactionTable() {
  using C = CompactionDef;
  static const SettingsTable<C> table = [] {
    SettingsTable<C> t("compaction");
    t.number("dt", &C::dt, Range::atLeast(0.0), "t0", "time step; 0 = the fixed step from the deposit's drop")
        .flag("adaptive_dt", &C::adaptiveDt, "adaptive time step, never below dt")
        .number("time_limit", &C::timeLimit, Range::leftOpen(0.0, kMaxTimeLimit), "t0",
                "simulated time after which the run stops unequilibrated (quasi-static: the fall hands over)")
        .number("fall_time_limit", &C::fallTimeLimit, Range::closed(0.0, kMaxTimeLimit), "t0",
                "quasi-static: the longest fall before the finisher takes over; 0 = time_limit")
        .integer("check_interval", &C::checkInterval, Range::atLeast(1), "-", "steps between equilibrium checks")
        .integer("frame_interval", &C::frameInterval, Range::atLeast(0), "-",
                 "steps between ParaView frames; 0 = first and last only")
        .number("force_ratio", &C::forceRatio, Range::positive(), "-", "equilibrium: |sum F| < force_ratio d^2 P")
        .number("moment_ratio", &C::momentRatio, Range::positive(), "-", "equilibrium: |sum M| < moment_ratio d^3 P")
        .number("kinetic_ratio", &C::kineticRatio, Range::positive(), "-", "equilibrium: E_k < kinetic_ratio d^3 P")
        .choice("protocol", &C::protocol, {{"dynamic", Protocol::Dynamic}, {"quasi-static", Protocol::QuasiStatic}},
                "time steps to equilibrium, or time steps until the fall is over then the finisher")
        .number("switch_kinetic_ratio", &C::switchKineticRatio, Range::positive(), "-",
                "quasi-static: hand over when the mean kinetic ratio is below this")
        .number("trust_radius", &C::trustRadius, Range::leftOpen(0.0, 0.5), "smallest grain size",
                "quasi-static: largest motion of a grain's surface in one finisher step")
        .number("settle_tolerance", &C::settleTolerance, Range::positive(), "smallest grain size",
                "quasi-static: the finisher has converged when its last step moved no grain more")
        .number("finisher_max_step", &C::finisherMaxStep, Range::positive(), "t0", "quasi-static: longest finisher step")
        .integer("finisher_max_steps", &C::finisherMaxSteps, Range::atLeast(1), "-",
                 "quasi-static: finisher steps after which the run stops unequilibrated");
    return t;
  }();
  return table;
}

void to_json(json& j, const CompactionDef& c) { j = compactionTable().write(c); }

void from_json(const json& j, CompactionDef& c) {
  c = CompactionDef{};
  compactionTable().read(j, c);
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
  if (j.contains("box")) knownKeysOnly(j.at("box"), json(d.box), fmt::format("{}.box", w));
  if (j.contains("population")) knownKeysOnly(j.at("population"), json(d.population), fmt::format("{}.population", w));
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
    throw std::invalid_argument(fmt::format("{}.seed: must be an integer >= 0 (got {})", w, jsonExcerpt(j.at("seed"))));
  c.seed = valueOr(j, w, "seed", d.seed);
  if (j.contains("threads") && !j.at("threads").is_number_integer())
    throw std::invalid_argument(
        fmt::format("{}.threads: must be an integer (got {})", w, jsonExcerpt(j.at("threads"))));
  c.threads = valueOr(j, w, "threads", d.threads);
}

void RunConfig::validate() const {
  box.validate();
  population.validate();
  if (std::find(kBackendNames.begin(), kBackendNames.end(), backend) == kBackendNames.end())
    throw std::invalid_argument("backend: " + unknownBackendMessage(backend));
  if (!backendOptions.is_object())
    throw std::invalid_argument(
        fmt::format("backend_options: must be a JSON object (got {})", jsonExcerpt(backendOptions)));
  if (threads < 1) throw std::invalid_argument(fmt::format("threads: must be >= 1 (got {})", threads));
  deposition.validate();
  compactionTable().validate(compaction);
  const double grains = estimatedGrainCount();
  if (grains > static_cast<double>(deposition.maxGrains))
    throw std::invalid_argument(fmt::format(
        "deposition: about {:.3g} grains for this box, more than max_grains ({}); check the box's size, or raise "
        "the limit with --max-grains (deposition.max_grains)",
        grains, deposition.maxGrains));
}

double RunConfig::estimatedGrainCount() const {
  if (deposition.grainCount > 0) return static_cast<double>(deposition.grainCount);
  const double volume = deposition.expectedSolidFraction * box.lengthX * box.width * box.height;
  const double small = population.smallFraction / 100.0;
  return volume * (1.0 - small) / population.meanGrainVolume(population.largeSize) +
         (small > 0.0 ? volume * small / population.meanGrainVolume(population.smallSize) : 0.0);
}

}  // namespace confpack::core
