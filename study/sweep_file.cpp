// The sweep file (docs/sweeps.md; study/sweep.hpp): reading a sweep JSON and validating every
// field of it, the base configuration, the named axes and the setting axes by their paths in the
// run configuration, and the number of runs it lists against --max-runs.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "backends/backend_factory.hpp"
#include "core/backend.hpp"
#include "core/input_document.hpp"
#include "core/json_input.hpp"
#include "study/sweep.hpp"
#include "study/sweep_internal.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using core::refuseInput;
using nlohmann::json;

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
    if (!known.contains(key)) core::refuseUnknownKey(source, path, key, core::keyList(known));
    const json& k = known.at(key);
    if (value.is_object() && k.is_object() && !k.empty())
      checkKnownKeys(value, k, path.empty() ? key : path + "." + key, source);
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
    refuseInput(source, "base", e.what());
  }
  core::to_json(merged, core::RunConfig{});
  checkKnownKeys(base, merged, "base", source);
  merged.merge_patch(base);
  core::RunConfig cfg;
  try {
    core::from_json(merged, cfg);
  } catch (const std::exception& e) {
    refuseInput(source, "base", e.what());
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
    refuseInput(source, where,
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

// The keys of a configuration path ("population.pinacoid.alpha_deg"), none of them empty.
std::vector<std::string> configPathKeys(const std::string& path, const std::string& field, std::string_view source) {
  std::vector<std::string> keys;
  for (std::size_t at = 0;;) {
    const std::size_t dot = path.find('.', at);
    keys.push_back(path.substr(at, dot == std::string::npos ? std::string::npos : dot - at));
    if (dot == std::string::npos) break;
    at = dot + 1;
  }
  for (const std::string& k : keys)
    if (k.empty())
      refuseInput(source, field,
                  "not a configuration path (keys of config.json joined by '.', e.g. population.pinacoid.alpha_deg)");
  return keys;
}

// backend_options.KEY: the backends' own settings tables, a value valid when one of the backends
// reads it (the expansion checks each run against its own backend).
SettingAxis parseBackendOptionAxis(const std::string& path, const std::string& key, const json& list,
                                   const std::string& field, std::string_view source) {
  SettingAxis axis{path, {}};
  for (const json& v : list) {
    std::string why;
    for (std::string_view backend : core::kBackendNames) {
      try {
        backends::checkBackendOptions(backend, json{{key, v}});
        why.clear();
        break;
      } catch (const std::invalid_argument& e) {
        // An unknown key is the least telling reason: keep a backend's objection to the value.
        if (why.empty() || why.find(": unknown key") != std::string::npos) why = e.what();
      }
    }
    if (!why.empty()) refuseInput(source, field, why);
    axis.values.push_back(v);
  }
  return axis;
}

// The setting that `keys` name in `defaults` (the resolved base as JSON): a known path that ends at
// a setting, not a section.
const json& settingNode(const std::vector<std::string>& keys, const std::string& field, std::string_view source,
                        const json& defaults) {
  const json* node = &defaults;
  std::string here;
  for (const std::string& k : keys) {
    if (!node->is_object() || !node->contains(k)) {
      if (here.empty())
        refuseInput(
            source, field,
            fmt::format("unknown key (known: width, shape, small_fraction, wall_friction, seed, replicas, backend, "
                        "or a path of the run configuration under {})",
                        core::keyList(*node)));
      if (!node->is_object())
        refuseInput(source, field, fmt::format("unknown configuration path: {} is a setting, not a section", here));
      refuseInput(source, field,
                  fmt::format("unknown configuration path: {} has no key {} (its keys: {})", here, core::textExcerpt(k),
                              core::keyList(*node)));
    }
    here += (here.empty() ? "" : ".") + k;
    node = &node->at(k);
  }
  if (node->is_object())
    refuseInput(source, field,
                node->empty() ? fmt::format("{} is a section: give one of its keys, {}.KEY", here, here)
                              : fmt::format("{} is a section, not a setting: give one of its keys ({})", here,
                                            core::keyList(*node)));
  return *node;
}

// A key of a group that is not a named axis: a path of the run configuration. It must name a
// setting the configuration's readers know (walked in `defaults`, the resolved base as JSON), or a
// backend option one of the backends knows; and each value must be read by them, so that a typo
// in a path or a value is refused before any run, by its name. Ranges that depend on other
// settings (a pinacoid's alpha against its E) are the expansion's to check, run by run.
SettingAxis parseSettingAxis(const std::string& path, const json& list, const std::string& field,
                             std::string_view source, const json& defaults) {
  const std::vector<std::string> keys = configPathKeys(path, field, source);
  if (keys.front() == "backend_options" && keys.size() > 2)
    refuseInput(source, field,
                "a backend option is one key deep: backend_options.KEY (confpack options nscd, or bullet)");
  if (keys.front() == "backend_options" && keys.size() == 2)
    return parseBackendOptionAxis(path, keys[1], list, field, source);
  const json& node = settingNode(keys, field, source, defaults);
  SettingAxis axis{path, {}};
  for (const json& v : list) {
    // The readers of some sections take any JSON type and fail with the library's words: say it
    // plainly first.
    const char* expected = node.is_number()    ? (v.is_number() || v.is_null() ? nullptr : "a number")
                           : node.is_string()  ? (v.is_string() ? nullptr : "a string")
                           : node.is_boolean() ? (v.is_boolean() ? nullptr : "true or false")
                                               : nullptr;
    if (expected) refuseInput(source, field, fmt::format("expected {} (got {})", expected, core::jsonExcerpt(v)));
    json cfg = defaults;
    json* at = &cfg;
    for (const std::string& k : keys) at = &(*at)[k];
    *at = v;
    try {
      core::RunConfig c;
      core::from_json(cfg, c);
    } catch (const std::exception& e) {
      refuseInput(source, field, e.what());
    }
    axis.values.push_back(v);
  }
  return axis;
}

// The values of a named axis into `out`; false when `key` names none (a setting's path).
bool parseNamedAxis(const std::string& key, const json& list, const std::string& field, std::string_view source,
                    SweepGroup& out) {
  if (key == "width") {
    for (const json& v : list) {
      if (v.is_string() && v.get<std::string>() == "biperiodic") {
        out.widths.push_back({0.0, true});  // period filled in by parseSweepSpec
      } else if (v.is_number() && v.get<double>() > 0.0 && std::isfinite(v.get<double>())) {
        out.widths.push_back({v.get<double>(), false});
      } else {
        refuseInput(source, field,
                    fmt::format("expected a positive number or \"biperiodic\" (got {})", core::jsonExcerpt(v)));
      }
    }
  } else if (key == "shape") {
    for (const json& v : list) {
      const std::string why = fmt::format("expected \"sphere\" or \"pinacoid\" (got {})", core::jsonExcerpt(v));
      if (!v.is_string()) refuseInput(source, field, why);
      try {
        out.shapes.push_back(core::shapeFromString(v.get<std::string>()));
      } catch (const std::invalid_argument&) {
        refuseInput(source, field, why);
      }
    }
  } else if (key == "small_fraction") {
    for (const json& v : list) {
      if (!v.is_number() || !(v.get<double>() >= 0.0 && v.get<double>() <= 100.0))
        refuseInput(source, field, fmt::format("x_S must be a number in [0, 100] (got {})", core::jsonExcerpt(v)));
      out.smallFractions.push_back(v.get<double>());
    }
  } else if (key == "wall_friction") {
    for (const json& v : list) {
      if (!v.is_number() || !(v.get<double>() >= 0.0) || !std::isfinite(v.get<double>()))
        refuseInput(source, field, fmt::format("mu_w must be a number >= 0 (got {})", core::jsonExcerpt(v)));
      out.wallFrictions.push_back(v.get<double>());
    }
  } else if (key == "seed") {
    for (const json& v : list) {
      if (!v.is_number_integer() || v.get<std::int64_t>() < 0)
        refuseInput(source, field, fmt::format("seeds must be non-negative integers (got {})", core::jsonExcerpt(v)));
      out.seeds.push_back(v.get<std::uint64_t>());
    }
  } else if (key == "backend") {
    const auto& names = core::kBackendNames;
    for (const json& v : list) {
      if (!v.is_string() || std::find(names.begin(), names.end(), v.get<std::string>()) == names.end())
        refuseInput(source, field, fmt::format("unknown backend {} (known: nscd, bullet)", core::jsonExcerpt(v)));
      out.backends.push_back(v.get<std::string>());
    }
  } else {
    return false;
  }
  return true;
}

// A group's "replicas": n, as seeds 1..n, so that "replicas": 3 and "seed": [1, 2, 3] name the
// same runs; counted against `maxRuns` before they are listed.
void addReplicas(const core::ObjectReader& group, std::size_t maxRuns, SweepGroup& out) {
  if (group.has("seed")) group.refuse("replicas", "give either seed or replicas, not both");
  const json& r = group.at("replicas");
  if (!r.is_number_integer() || r.get<std::int64_t>() < 1)
    group.refuse("replicas", fmt::format("expected an integer >= 1 (got {})", core::jsonExcerpt(r)));
  checkRunCount(listedRuns(out, static_cast<double>(r.get<std::int64_t>())), maxRuns, group.source(), group.path());
  for (std::int64_t s = 1; s <= r.get<std::int64_t>(); ++s) out.seeds.push_back(static_cast<std::uint64_t>(s));
}

SweepGroup parseGroup(const json& g, const std::string& where, std::string_view source, std::size_t maxRuns,
                      const json& defaults) {
  const core::ObjectReader group(g, source, where);
  SweepGroup out;
  for (const auto& [key, raw] : g.items()) {
    const std::string field = where + "." + core::textExcerpt(key);
    if (key == "replicas") continue;
    const json list = asList(raw);
    if (list.empty()) refuseInput(source, field, "empty list");
    if (!parseNamedAxis(key, list, field, source, out))
      out.settings.push_back(parseSettingAxis(key, list, field, source, defaults));
  }
  for (const auto& [name, path] : namedAxisPaths())
    if (group.has(name) && group.has(path))
      group.refuse(path, fmt::format("{} and {} vary the same setting: give one of them", name, path));
  if (group.has("replicas")) addReplicas(group, maxRuns, out);
  return out;
}

// A sweep-level backend key whose one accepted value is "nscd"; `what` says why, in the message.
std::string nscdOnly(const core::ObjectReader& doc, const char* key, std::string_view what) {
  const json& w = doc.at(key);
  if (w != "nscd") doc.refuse(key, fmt::format("expected \"nscd\", {} (got {})", what, core::jsonExcerpt(w)));
  return w.get<std::string>();
}

// The sweep's name, base, biperiodic width, settle_with and equal_time, each optional.
void readSweepSettings(const core::ObjectReader& doc, SweepSpec& spec) {
  if (doc.has("name")) {
    spec.name = doc.string("name");
    if (spec.name.empty()) doc.refuse("name", "must be a non-empty string (got \"\")");
  }
  if (doc.has("base")) {
    const json& base = doc.object("base");
    try {  // a base written before the walls had their own object: mu_w moved to walls.friction
      spec.base = core::withWallsMoved(base);
    } catch (const std::exception& e) {
      doc.refuse("base", e.what());
    }
  }
  resolveBase(spec.base, doc.source());  // refuse a bad base before anything else
  if (doc.has("biperiodic_width")) spec.biperiodicWidth = doc.number("biperiodic_width", core::Range::positive());
  // Only nscd has the quasi-static finisher that brings a pile to rest whatever its state, and only
  // its runs have a fall of their own length (to rest, then the finisher).
  if (doc.has("settle_with")) spec.settleWith = nscdOnly(doc, "settle_with", "the backend with a finisher");
  if (doc.has("equal_time")) spec.equalTime = nscdOnly(doc, "equal_time", "the backend whose fall sets the time");
}

// The groups of runs: "vary" (one product) or "groups" (a list of products).
void readSweepGroups(const core::ObjectReader& doc, std::size_t maxRuns, SweepSpec& spec) {
  if (doc.has("vary") == doc.has("groups"))
    doc.refuse("vary", "give exactly one of \"vary\" (one product) or \"groups\" (a list of products)");
  const json defaults = mergedBase(spec.base);
  if (doc.has("vary")) {
    spec.groups.push_back(parseGroup(doc.at("vary"), "vary", doc.source(), maxRuns, defaults));
  } else {
    const json& groups = doc.array("groups");
    if (groups.empty()) doc.refuse("groups", "must hold at least one group (an object of value lists)");
    for (std::size_t i = 0; i < groups.size(); ++i)
      spec.groups.push_back(parseGroup(groups[i], fmt::format("groups[{}]", i), doc.source(), maxRuns, defaults));
  }
  double runs = 0.0;
  for (const SweepGroup& g : spec.groups) runs += listedRuns(g, static_cast<double>(g.seeds.size()));
  checkRunCount(runs, maxRuns, doc.source(), doc.has("vary") ? "vary" : "groups");
}

}  // namespace

SweepSpec parseSweepSpec(const json& doc, std::string_view source, std::size_t maxRuns) {
  const core::ObjectReader top = core::readDocument(
      doc, source, {kSweepFormat, kSweepVersion, core::HeaderKey::Optional, core::HeaderKey::Optional},
      {"format", "version", "name", "description", "base", "biperiodic_width", "vary", "groups", "settle_with",
       "equal_time"});
  SweepSpec spec;
  spec.source = doc;
  readSweepSettings(top, spec);
  readSweepGroups(top, maxRuns, spec);
  for (SweepGroup& g : spec.groups)
    for (WidthChoice& w : g.widths)
      if (w.periodicY) w.width = spec.biperiodicWidth;
  return spec;
}

SweepSpec readSweepSpec(const fs::path& path, std::size_t maxRuns) {
  return parseSweepSpec(core::readJsonFile(path, "sweep file"), path.string(), maxRuns);
}

}  // namespace confpack::study
