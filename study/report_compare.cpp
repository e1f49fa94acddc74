#include "study/report_compare.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <set>
#include <stdexcept>

namespace confpack::study {

using nlohmann::json;

std::string ComparedSetting::sideOf(const SweepRun& run) const {
  return backend() ? run.config.backend : settingText(run.config, key);
}

std::vector<std::string> ComparedSetting::familySettings(const std::vector<SweepRun>& tableRuns) const {
  std::vector<std::string> out = variedSettings(tableRuns);
  if (backend()) return out;
  std::erase(out, key);
  const bool backendsDiffer = std::any_of(tableRuns.begin(), tableRuns.end(), [&](const SweepRun& r) {
    return r.config.backend != tableRuns.front().config.backend;
  });
  // variedSettings lists its paths in order; "backend" takes its place among them.
  if (backendsDiffer) out.insert(std::lower_bound(out.begin(), out.end(), std::string("backend")), "backend");
  return out;
}

ComparedSetting compareSetting(const std::string& key, const std::vector<SweepRun>& tableRuns) {
  const std::string what = "--compare " + key;
  if (key.empty())
    throw std::invalid_argument(
        "--compare: no key given; name a setting by its path in config.json, e.g. backend or backend_options.solver");
  // Each of these makes families of its own (and W is the abscissa of the fits): its two values
  // would never meet in one family.
  static const std::set<std::string> familyAxes = {"box.width", "box.periodic_y", "population.shape",
                                                   "population.small_fraction", "walls.friction"};
  if (familyAxes.count(key))
    throw std::invalid_argument(fmt::format(
        "{}: the report's families are told apart by {} (W, biperiodic, shape, x_S and mu_w each make families of "
        "their own); compare a setting the families share",
        what, key));
  std::vector<std::string> values;  // in the table's order
  std::vector<const SweepRun*> lacking;
  for (const SweepRun& r : tableRuns) {
    json cfg;
    core::to_json(cfg, r.config);
    const json* at = settingAt(cfg, key);
    if (!at) {
      lacking.push_back(&r);
      continue;
    }
    if (at->is_object()) {
      std::vector<std::string> keys;
      for (const auto& [k, _] : at->items()) keys.push_back(k);
      throw std::invalid_argument(fmt::format("{}: {} is a section of the run configuration ({}), not a setting", what,
                                              key, fmt::join(keys, ", ")));
    }
    const std::string value = settingText(cfg, key);
    if (std::find(values.begin(), values.end(), value) == values.end()) values.push_back(value);
  }
  if (!tableRuns.empty() && lacking.size() == tableRuns.size())
    throw std::invalid_argument(fmt::format(
        "{}: no run's configuration has {} (a run's config.json shows every key its configuration has)", what, key));
  if (!lacking.empty())
    throw std::invalid_argument(fmt::format("{}: run {} has no {} in its configuration ({} of the {} runs lack it)",
                                            what, lacking.front()->name, key, lacking.size(), tableRuns.size()));
  if (values.size() != 2)
    throw std::invalid_argument(fmt::format("{}: the runs have {} value{} of {}{}; a comparison needs exactly two",
                                            what, values.size(), values.size() == 1 ? "" : "s", key,
                                            values.empty() ? "" : fmt::format(" ({})", fmt::join(values, ", "))));
  ComparedSetting out;
  out.key = key;
  if (!out.backend()) {
    out.column = settingNames({key}).front();
    out.noun = "value of " + out.column;
    out.plural = "values of " + out.column;
  }
  return out;
}

}  // namespace confpack::study
