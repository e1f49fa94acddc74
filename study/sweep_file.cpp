// The sweep file (docs/sweeps.md; study/sweep.hpp): reading a sweep JSON and validating every
// field of it, the base configuration, the named axes and the setting axes by their paths in the
// run configuration, and the number of runs it lists against --max-runs.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>

#include "backends/backend_factory.hpp"
#include "core/backend.hpp"
#include "core/json_input.hpp"
#include "study/sweep.hpp"
#include "study/sweep_internal.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

[[noreturn]] void bad(std::string_view source, std::string_view field, std::string_view what) {
  throw std::invalid_argument(fmt::format("{}: {}: {}", source, field, what));
}

namespace {

// A list value may be given as a scalar for convenience ("backend": "nscd").
json asList(const json& v) {
  return v.is_array() ? v : json::array({v});
}

// Keys of `given` that the configuration does not know are typos: refuse them rather than
// silently running the default. Recurses where both sides are objects; an object that is empty by
// default (backend_options) is free-form and left to its owner to check.
void checkKnownKeys(const json& given, const json& known, const std::string& path, std::string_view source) {
  for (const auto& [key, value] : given.items()) {
    const std::string here = path.empty() ? core::textExcerpt(key) : path + "." + core::textExcerpt(key);
    if (!known.contains(key)) bad(source, here, "unknown key");
    const json& k = known.at(key);
    if (value.is_object() && k.is_object() && !k.empty()) checkKnownKeys(value, k, here, source);
  }
}

// The default configuration with the base's keys over it, as JSON: what a path of a setting
// axis is walked in.
json mergedBase(const json& base) {
  json merged;
  core::to_json(merged, core::RunConfig{});
  merged.merge_patch(base);
  return merged;
}

}  // namespace

core::RunConfig resolveBase(const json& given, std::string_view source) {
  json merged, base;
  try {
    base = core::withWallsMoved(given);
  } catch (const std::exception& e) {
    bad(source, "base", e.what());
  }
  core::to_json(merged, core::RunConfig{});
  checkKnownKeys(base, merged, "base", source);
  merged.merge_patch(base);
  core::RunConfig cfg;
  try {
    core::from_json(merged, cfg);
  } catch (const std::exception& e) {
    bad(source, "base", e.what());
  }
  return cfg;
}

namespace {

// Runs a group lists: the product of its list sizes, an empty list (the base value) counting once;
// `seeds` replaces the size of the seed list (replicas are counted before they are listed).
// In double: the product of a few large lists must not wrap around.
double listedRuns(const SweepGroup& g, double seeds) {
  auto count = [](std::size_t n) { return static_cast<double>(std::max<std::size_t>(n, 1)); };
  double settings = 1.0;
  for (const SettingAxis& a : g.settings) settings *= count(a.values.size());
  return count(g.widths.size()) * count(g.shapes.size()) * count(g.smallFractions.size()) *
         count(g.wallFrictions.size()) * count(g.backends.size()) * std::max(seeds, 1.0) * settings;
}

void checkRunCount(double runs, std::size_t maxRuns, std::string_view source, std::string_view where) {
  if (runs > static_cast<double>(maxRuns))
    bad(source, where,
        fmt::format("lists {:.6g} runs, more than the limit of {} (check the lists and replicas, or raise the "
                    "limit with --max-runs)",
                    runs, maxRuns));
}

// The named axes and the configuration paths they set: a group may not give both names of one.
const std::vector<std::pair<std::string, std::string>>& namedAxisPaths() {
  static const std::vector<std::pair<std::string, std::string>> m = {{"width", "box.width"},
                                                                     {"width", "box.periodic_y"},
                                                                     {"shape", "population.shape"},
                                                                     {"small_fraction", "population.small_fraction"},
                                                                     {"wall_friction", "walls.friction"}};
  return m;
}

std::string keysOf(const json& section) {
  std::string keys;
  for (const auto& [k, _] : section.items()) keys += (keys.empty() ? "" : ", ") + k;
  return keys;
}

// A key of a group that is not a named axis: a path of the run configuration. It must name a
// setting the configuration's readers know (walked in `defaults`, the resolved base as JSON), or a
// backend option one of the backends knows; and each value must be read by them, so that a typo
// in a path or a value is refused before any run, by its name. Ranges that depend on other
// settings (a pinacoid's alpha against its E) are the expansion's to check, run by run.
SettingAxis parseSettingAxis(const std::string& path, const json& list, const std::string& field,
                             std::string_view source, const json& defaults) {
  SettingAxis axis{path, {}};
  std::vector<std::string> keys;
  for (std::size_t at = 0;;) {
    const std::size_t dot = path.find('.', at);
    keys.push_back(path.substr(at, dot == std::string::npos ? std::string::npos : dot - at));
    if (dot == std::string::npos) break;
    at = dot + 1;
  }
  for (const std::string& k : keys)
    if (k.empty())
      bad(source, field,
          "not a configuration path (keys of config.json joined by '.', e.g. population.pinacoid.alpha_deg)");

  if (keys.front() == "backend_options" && keys.size() > 2)
    bad(source, field, "a backend option is one key deep: backend_options.KEY (confpack options nscd, or bullet)");
  if (keys.front() == "backend_options" && keys.size() == 2) {
    // Backend options are the backends' own settings tables: a value is valid when one of the
    // backends reads it (the expansion checks each run against its own backend).
    for (const json& v : list) {
      std::string why;
      for (std::string_view backend : core::kBackendNames) {
        try {
          backends::checkBackendOptions(backend, json{{keys[1], v}});
          why.clear();
          break;
        } catch (const std::invalid_argument& e) {
          // An unknown key is the least telling reason: keep a backend's objection to the value.
          if (why.empty() || why.find(": unknown key") != std::string::npos) why = e.what();
        }
      }
      if (!why.empty()) bad(source, field, why);
      axis.values.push_back(v);
    }
    return axis;
  }

  const json* node = &defaults;
  std::string here;
  for (const std::string& k : keys) {
    if (!node->is_object() || !node->contains(k)) {
      if (here.empty())
        bad(source, field,
            fmt::format("unknown key (known: width, shape, small_fraction, wall_friction, seed, replicas, backend, "
                        "or a path of the run configuration under {})",
                        keysOf(*node)));
      if (!node->is_object())
        bad(source, field, fmt::format("unknown configuration path: {} is a setting, not a section", here));
      bad(source, field,
          fmt::format("unknown configuration path: {} has no key {} (its keys: {})", here, core::textExcerpt(k),
                      keysOf(*node)));
    }
    here += (here.empty() ? "" : ".") + k;
    node = &node->at(k);
  }
  if (node->is_object())
    bad(source, field,
        node->empty() ? fmt::format("{} is a section: give one of its keys, {}.KEY", here, here)
                      : fmt::format("{} is a section, not a setting: give one of its keys ({})", here, keysOf(*node)));
  for (const json& v : list) {
    // The readers of some sections take any JSON type and fail with the library's words: say it
    // plainly first.
    const char* expected = node->is_number()    ? (v.is_number() || v.is_null() ? nullptr : "a number")
                           : node->is_string()  ? (v.is_string() ? nullptr : "a string")
                           : node->is_boolean() ? (v.is_boolean() ? nullptr : "true or false")
                                                : nullptr;
    if (expected) bad(source, field, fmt::format("expected {} (got {})", expected, core::jsonExcerpt(v)));
    json cfg = defaults;
    json* at = &cfg;
    for (const std::string& k : keys) at = &(*at)[k];
    *at = v;
    try {
      core::RunConfig c;
      core::from_json(cfg, c);
    } catch (const std::exception& e) {
      bad(source, field, e.what());
    }
    axis.values.push_back(v);
  }
  return axis;
}

SweepGroup parseGroup(const json& g, const std::string& where, std::string_view source, std::size_t maxRuns,
                      const json& defaults) {
  if (!g.is_object()) bad(source, where, "expected an object of value lists");
  SweepGroup out;
  for (const auto& [key, raw] : g.items()) {
    const std::string field = where + "." + core::textExcerpt(key);
    if (key == "replicas") continue;
    const json list = asList(raw);
    if (list.empty()) bad(source, field, "empty list");
    if (key == "width") {
      for (const json& v : list) {
        if (v.is_string() && v.get<std::string>() == "biperiodic") {
          out.widths.push_back({0.0, true});  // period filled in by parseSweepSpec
        } else if (v.is_number() && v.get<double>() > 0.0 && std::isfinite(v.get<double>())) {
          out.widths.push_back({v.get<double>(), false});
        } else {
          bad(source, field,
              fmt::format("expected a positive number or \"biperiodic\" (got {})", core::jsonExcerpt(v)));
        }
      }
    } else if (key == "shape") {
      for (const json& v : list) {
        if (!v.is_string())
          bad(source, field, fmt::format("expected \"sphere\" or \"pinacoid\" (got {})", core::jsonExcerpt(v)));
        try {
          out.shapes.push_back(core::shapeFromString(v.get<std::string>()));
        } catch (const std::invalid_argument&) {
          bad(source, field, fmt::format("expected \"sphere\" or \"pinacoid\" (got {})", core::jsonExcerpt(v)));
        }
      }
    } else if (key == "small_fraction") {
      for (const json& v : list) {
        if (!v.is_number() || !(v.get<double>() >= 0.0 && v.get<double>() <= 100.0))
          bad(source, field, fmt::format("x_S must be a number in [0, 100] (got {})", core::jsonExcerpt(v)));
        out.smallFractions.push_back(v.get<double>());
      }
    } else if (key == "wall_friction") {
      for (const json& v : list) {
        if (!v.is_number() || !(v.get<double>() >= 0.0) || !std::isfinite(v.get<double>()))
          bad(source, field, fmt::format("mu_w must be a number >= 0 (got {})", core::jsonExcerpt(v)));
        out.wallFrictions.push_back(v.get<double>());
      }
    } else if (key == "seed") {
      for (const json& v : list) {
        if (!v.is_number_integer() || v.get<std::int64_t>() < 0)
          bad(source, field, fmt::format("seeds must be non-negative integers (got {})", core::jsonExcerpt(v)));
        out.seeds.push_back(v.get<std::uint64_t>());
      }
    } else if (key == "backend") {
      const auto& names = core::kBackendNames;
      for (const json& v : list) {
        if (!v.is_string() || std::find(names.begin(), names.end(), v.get<std::string>()) == names.end())
          bad(source, field, fmt::format("unknown backend {} (known: nscd, bullet)", core::jsonExcerpt(v)));
        out.backends.push_back(v.get<std::string>());
      }
    } else {
      out.settings.push_back(parseSettingAxis(key, list, field, source, defaults));
    }
  }
  for (const auto& [name, path] : namedAxisPaths())
    if (g.contains(name) && g.contains(path))
      bad(source, where + "." + path, fmt::format("{} and {} vary the same setting: give one of them", name, path));
  if (g.contains("replicas")) {
    if (g.contains("seed")) bad(source, where + ".replicas", "give either seed or replicas, not both");
    const json& r = g.at("replicas");
    if (!r.is_number_integer() || r.get<std::int64_t>() < 1)
      bad(source, where + ".replicas", fmt::format("expected an integer >= 1 (got {})", core::jsonExcerpt(r)));
    checkRunCount(listedRuns(out, static_cast<double>(r.get<std::int64_t>())), maxRuns, source, where);
    // Replicas are seeds 1..n, so that "replicas": 3 and "seed": [1, 2, 3] name the same runs.
    for (std::int64_t s = 1; s <= r.get<std::int64_t>(); ++s) out.seeds.push_back(static_cast<std::uint64_t>(s));
  }
  return out;
}

}  // namespace

SweepSpec parseSweepSpec(const json& doc, std::string_view source, std::size_t maxRuns) {
  if (!doc.is_object()) bad(source, "(document)", "expected a JSON object");
  static const std::set<std::string> known = {"format", "version", "name",        "base",       "biperiodic_width",
                                              "vary",   "groups",  "description", "settle_with"};
  for (const auto& [key, v] : doc.items())
    if (!known.count(key))
      bad(source, core::textExcerpt(key),
          "unknown key (known: format, version, name, description, base, biperiodic_width, vary, groups, "
          "settle_with)");
  if (doc.contains("format") && doc.at("format") != kSweepFormat)
    bad(source, "format", fmt::format("expected \"{}\"", kSweepFormat));
  if (doc.contains("version") && doc.at("version") != kSweepVersion)
    bad(source, "version", fmt::format("expected {}", kSweepVersion));

  SweepSpec spec;
  spec.source = doc;
  if (doc.contains("name")) {
    if (!doc.at("name").is_string() || doc.at("name").get<std::string>().empty())
      bad(source, "name", "expected a non-empty string");
    spec.name = doc.at("name").get<std::string>();
  }
  if (doc.contains("base")) {
    if (!doc.at("base").is_object()) bad(source, "base", "expected an object (a run configuration)");
    try {  // a base written before the walls had their own object: mu_w moved to walls.friction
      spec.base = core::withWallsMoved(doc.at("base"));
    } catch (const std::exception& e) {
      bad(source, "base", e.what());
    }
  }
  resolveBase(spec.base, source);  // refuse a bad base before anything else
  if (doc.contains("biperiodic_width")) {
    const json& w = doc.at("biperiodic_width");
    if (!w.is_number() || !(w.get<double>() > 0.0))
      bad(source, "biperiodic_width", fmt::format("expected a positive number (got {})", core::jsonExcerpt(w)));
    spec.biperiodicWidth = w.get<double>();
  }
  if (doc.contains("settle_with")) {
    // Only nscd has the quasi-static finisher that brings a pile to rest whatever its state.
    const json& w = doc.at("settle_with");
    if (w != "nscd")
      bad(source, "settle_with",
          fmt::format("expected \"nscd\", the backend with a finisher (got {})", core::jsonExcerpt(w)));
    spec.settleWith = w.get<std::string>();
  }
  if (doc.contains("vary") == doc.contains("groups"))
    bad(source, "vary", "give exactly one of \"vary\" (one product) or \"groups\" (a list of products)");
  const json defaults = mergedBase(spec.base);
  if (doc.contains("vary")) {
    spec.groups.push_back(parseGroup(doc.at("vary"), "vary", source, maxRuns, defaults));
  } else {
    const json& groups = doc.at("groups");
    if (!groups.is_array() || groups.empty()) bad(source, "groups", "expected a non-empty list of objects");
    for (std::size_t i = 0; i < groups.size(); ++i)
      spec.groups.push_back(parseGroup(groups[i], fmt::format("groups[{}]", i), source, maxRuns, defaults));
  }
  double runs = 0.0;
  for (const SweepGroup& g : spec.groups) runs += listedRuns(g, static_cast<double>(g.seeds.size()));
  checkRunCount(runs, maxRuns, source, doc.contains("vary") ? "vary" : "groups");
  for (SweepGroup& g : spec.groups)
    for (WidthChoice& w : g.widths)
      if (w.periodicY) w.width = spec.biperiodicWidth;
  return spec;
}

SweepSpec readSweepSpec(const fs::path& path, std::size_t maxRuns) {
  return parseSweepSpec(core::readJsonFile(path, "sweep file"), path.string(), maxRuns);
}

}  // namespace confpack::study
