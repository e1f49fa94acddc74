// The run table (study/sweep.hpp): a sweep's groups expanded into runs in a fixed order, each with
// its stable name, its resolved and validated configuration and its deposit; the settings the runs
// vary and their short names, a run's label and family; the slices of a job array; equal_time's
// partners.
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

#include "backends/backend_factory.hpp"
#include "core/settings_table.hpp"
#include "study/sweep.hpp"
#include "study/sweep_internal.hpp"

namespace confpack::study {

using nlohmann::json;

namespace {

// What the deposition sees: the box's geometry (placement is purely geometric, whatever the
// walls' friction), the population, the deposition settings and the seed. Runs with equal keys
// share a deposit.
std::string depositKey(const core::RunConfig& cfg) {
  json box, pop, dep;
  core::to_json(box, cfg.box);
  core::to_json(pop, cfg.population);
  core::to_json(dep, cfg.deposition);
  return json{{"box", box}, {"population", pop}, {"deposition", dep}, {"seed", cfg.seed}}.dump();
}

// The leaves of a configuration's JSON, keyed by their path joined with '.'.
void flattenConfig(const json& j, const std::string& path, std::map<std::string, const json*>& out) {
  for (const auto& [key, v] : j.items()) {
    const std::string here = path.empty() ? key : path + "." + key;
    if (v.is_object())
      flattenConfig(v, here, out);
    else
      out[here] = &v;
  }
}

// The settings that differ between configurations given one by one as JSON (variedSettings):
// each against the first, leaf by leaf, a path varied where a value differs or one of the two
// lacks it. Paths are spelled out only where they differ, so a table of 100,000 runs is compared
// in about the time its configurations take to write as JSON.
class VariedSettings {
 public:
  void add(const json& cfg) {
    if (first_.is_null()) {
      first_ = cfg;
      return;
    }
    compare(cfg, first_, "");
    compare(first_, cfg, "");
  }
  // In path order, without those of the named axes (their own columns: W and biperiodic, shape,
  // x_S, mu_w, seed, backend).
  std::vector<std::string> paths() const {
    static const std::set<std::string> named = {
        "box.width",      "box.periodic_y", "population.shape", "population.small_fraction",
        "walls.friction", "seed",           "backend"};
    // A length_x fitted to one grain cap for every run follows from those axes too.
    const bool fitted = first_.is_object() && first_.contains("deposition") &&
                        first_.at("deposition").value("grain_cap", 0) > 0 && !varied_.count("deposition.grain_cap");
    std::vector<std::string> out;
    for (const std::string& p : varied_)
      if (!named.count(p) && !(fitted && p == "box.length_x")) out.push_back(p);
    return out;
  }

 private:
  void compare(const json& a, const json& b, const std::string& path) {
    for (const auto& [key, v] : a.items()) {
      const auto it = b.find(key);
      if (it != b.end() && !v.is_object() && v == *it) continue;  // the common case: no path spelled out
      const std::string here = path.empty() ? key : path + "." + key;
      if (it == b.end()) {
        // The whole subtree is missing from b.
        std::map<std::string, const json*> leaves;
        if (v.is_object())
          flattenConfig(v, here, leaves);
        else
          leaves[here] = &v;
        for (const auto& [p, _] : leaves) varied_.insert(p);
      } else if (v.is_object() && it->is_object()) {
        compare(v, *it, here);
      } else if (v != *it) {
        varied_.insert(here);
      }
    }
  }

  json first_;
  std::set<std::string> varied_;
};

// Every combination of the values of a group's setting axes, the first axis varying slowest; one
// empty combination when the group has none.
std::vector<std::vector<const json*>> settingCombinations(const std::vector<SettingAxis>& axes) {
  std::vector<std::vector<const json*>> out = {{}};
  for (const SettingAxis& a : axes) {
    std::vector<std::vector<const json*>> next;
    for (const auto& prefix : out)
      for (const json& v : a.values) {
        next.push_back(prefix);
        next.back().push_back(&v);
      }
    out = std::move(next);
  }
  return out;
}

// Sets each axis's value at its path of the run's configuration, through the configuration's
// JSON reader (the one config.json is read with).
void applySettings(SweepRun& r, const std::vector<SettingAxis>& axes, const std::vector<const json*>& values) {
  json cfg;
  core::to_json(cfg, r.config);
  for (std::size_t i = 0; i < axes.size(); ++i) {
    json* at = &cfg;
    for (std::size_t from = 0;;) {
      const std::size_t dot = axes[i].path.find('.', from);
      at = &(*at)[axes[i].path.substr(from, dot == std::string::npos ? std::string::npos : dot - from)];
      if (dot == std::string::npos) break;
      from = dot + 1;
    }
    *at = *values[i];
  }
  core::from_json(cfg, r.config);
}

// A run's configuration as text without what may differ between a run and its equal-time
// partner: the backend, its options and the time limit (which equal_time sets).
std::string partnerKey(const core::RunConfig& cfg) {
  json j;
  core::to_json(j, cfg);
  j.erase("backend");
  j.erase("backend_options");
  j["compaction"].erase("time_limit");
  return j.dump();
}

}  // namespace

std::string SweepRun::depositName() const {
  return fmt::format("d{:04d}", depositIndex);
}

std::string familyName(const core::RunConfig& cfg) {
  const bool bidisperse = cfg.population.smallFraction > 0.0;
  const char* grains = cfg.population.shape == core::ShapeKind::Sphere ? "SP" : "PP";
  return fmt::format("{}{}", bidisperse ? "B" : "M", grains);
}

const json* settingAt(const json& cfg, const std::string& path) {
  const json* at = &cfg;
  for (std::size_t from = 0;;) {
    const std::size_t dot = path.find('.', from);
    const std::string key = path.substr(from, dot == std::string::npos ? std::string::npos : dot - from);
    if (!at->is_object() || !at->contains(key)) return nullptr;
    at = &at->at(key);
    if (dot == std::string::npos) return at;
    from = dot + 1;
  }
}

std::string settingText(const json& cfg, const std::string& path) {
  const json* at = settingAt(cfg, path);
  if (!at) return "-";
  if (at->is_string()) return at->get<std::string>();
  // Shortest text that reads back as the same double ("45", "0.1", "1e-08"): runs that differ in
  // a setting must not share its text.
  if (at->is_number_float()) return fmt::format("{}", at->get<double>());
  if (at->is_null()) return "none";
  return at->dump();
}

std::string SweepRun::label(const std::vector<std::string>& settings) const {
  const std::string w = config.box.periodicY ? fmt::format("bi{}", core::numberText(config.box.width))
                                             : core::numberText(config.box.width);
  std::string text =
      fmt::format("{} xS={} W={} mu={} s{} {}", familyName(config), core::numberText(config.population.smallFraction),
                  w, core::numberText(config.walls.friction), config.seed, config.backend);
  if (settings.empty()) return text;
  const std::vector<std::string> names = settingNames(settings);
  json cfg;
  core::to_json(cfg, config);
  for (std::size_t i = 0; i < settings.size(); ++i)
    text += fmt::format(" {}={}", names[i], settingText(cfg, settings[i]));
  return text;
}

std::vector<std::string> variedSettings(const std::vector<SweepRun>& runs) {
  VariedSettings varied;
  for (const SweepRun& r : runs) {
    json cfg;
    core::to_json(cfg, r.config);
    varied.add(cfg);
  }
  return varied.paths();
}

std::string settingText(const core::RunConfig& cfg, const std::string& path) {
  json j;
  core::to_json(j, cfg);
  return settingText(j, path);
}

std::vector<std::string> settingNames(const std::vector<std::string>& paths) {
  // The last k keys of a path (the whole path when it has fewer).
  const auto tail = [](const std::string& path, std::size_t k) {
    std::size_t at = path.size();
    for (std::size_t i = 0; i < k; ++i) {
      const std::size_t dot = at == 0 ? std::string::npos : path.rfind('.', at - 1);
      if (dot == std::string::npos) return path;
      at = dot;
    }
    return path.substr(at + 1);
  };
  std::vector<std::string> names;
  for (const std::string& p : paths) {
    std::size_t k = 1;
    for (;; ++k) {
      const std::string name = tail(p, k);
      const bool unique =
          std::none_of(paths.begin(), paths.end(), [&](const std::string& q) { return q != p && tail(q, k) == name; });
      if (unique || name == p) break;
    }
    names.push_back(tail(p, k));
  }
  return names;
}

std::vector<SweepRun> expandRuns(const SweepSpec& spec) {
  const core::RunConfig base = resolveBase(spec.base, "sweep");
  bool hasBackendOptionAxis = false;
  for (const SweepGroup& g : spec.groups)
    for (const SettingAxis& a : g.settings)
      hasBackendOptionAxis = hasBackendOptionAxis || a.path.starts_with("backend_options.");
  std::vector<SweepRun> runs;
  std::set<std::string> seen;
  std::map<std::string, std::size_t> deposits;
  VariedSettings variedInTable;

  for (const SweepGroup& g : spec.groups) {
    // An empty list takes the base value; writing it as a one-element list keeps one loop nest.
    const auto shapes = g.shapes.empty() ? std::vector{base.population.shape} : g.shapes;
    const auto fractions = g.smallFractions.empty() ? std::vector{base.population.smallFraction} : g.smallFractions;
    const auto widths = g.widths.empty() ? std::vector{WidthChoice{base.box.width, base.box.periodicY}} : g.widths;
    const auto frictions = g.wallFrictions.empty() ? std::vector{base.walls.friction} : g.wallFrictions;
    const auto seeds = g.seeds.empty() ? std::vector{base.seed} : g.seeds;
    const auto backendList = g.backends.empty() ? std::vector{base.backend} : g.backends;
    const std::vector<std::vector<const json*>> settings = settingCombinations(g.settings);
    for (core::ShapeKind shape : shapes)
      for (double xs : fractions)
        for (const WidthChoice& w : widths)
          for (double mu : frictions)
            for (const std::vector<const json*>& values : settings)
              for (std::uint64_t seed : seeds)
                for (const std::string& backend : backendList) {
                  SweepRun r;
                  r.config = base;
                  r.config.population.shape = shape;
                  r.config.population.smallFraction = xs;
                  r.config.box.width = w.width;
                  r.config.box.periodicY = w.periodicY;
                  r.config.walls.friction = mu;
                  r.config.seed = seed;
                  r.config.backend = backend;
                  if (!values.empty()) applySettings(r, g.settings, values);
                  // A biperiodic box has no side walls: mu_w is meaningless there, and keeping it
                  // would make mu_w variants of the reference distinct runs of the same physics.
                  if (r.config.box.periodicY) r.config.walls.friction = 0.0;
                  r.config.fitLengthToGrainCap();  // after every axis: the count depends on all of them
                  json key;
                  core::to_json(key, r.config);
                  if (!seen.insert(key.dump()).second) continue;
                  variedInTable.add(key);
                  r.index = runs.size();
                  const auto [it, inserted] = deposits.try_emplace(depositKey(r.config), deposits.size());
                  r.depositIndex = it->second;
                  runs.push_back(std::move(r));
                }
  }
  const int digits = std::max<int>(4, static_cast<int>(std::to_string(runs.empty() ? 0 : runs.size() - 1).size()));
  const std::vector<std::string> varied = variedInTable.paths();
  for (SweepRun& r : runs) {
    r.name = fmt::format("r{:0{}d}", r.index, digits);
    try {
      r.config.validate();
      // A backend option set by an axis must be one of the run's own backend.
      if (hasBackendOptionAxis) backends::checkBackendOptions(r.config.backend, r.config.backendOptions);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("sweep run {} ({}): {}", r.name, r.label(varied), e.what()));
    }
  }
  return runs;
}

std::vector<std::optional<std::size_t>> equalTimePartners(const std::vector<SweepRun>& runs,
                                                          const std::string& backend) {
  std::vector<std::optional<std::size_t>> out(runs.size());
  if (backend.empty()) return out;
  std::map<std::string, std::size_t> partners;
  for (const SweepRun& r : runs)
    if (r.config.backend == backend) partners.try_emplace(partnerKey(r.config), r.index);
  for (const SweepRun& r : runs) {
    if (r.config.backend == backend) continue;
    const auto it = partners.find(partnerKey(r.config));
    if (it == partners.end())
      throw std::invalid_argument(
          fmt::format("equal_time: run {} ({}) has no {} run of the same configuration to take its time from", r.name,
                      r.label(), backend));
    out[r.index] = it->second;
  }
  return out;
}

std::vector<std::size_t> sliceRuns(const std::vector<SweepRun>& runs, std::size_t taskIndex, std::size_t taskCount) {
  if (taskCount == 0) throw std::invalid_argument("--task-count must be >= 1");
  if (taskIndex >= taskCount)
    throw std::invalid_argument(fmt::format("--task-index must be in [0, {}) (got {})", taskCount, taskIndex));
  std::vector<std::size_t> out;
  for (const SweepRun& r : runs)
    if (r.depositIndex % taskCount == taskIndex) out.push_back(r.index);
  return out;
}

}  // namespace confpack::study
