// The sweep folder on disk (study/sweep.hpp): SWEEPDIR/sweep.json, the run table's document,
// written once and checked against the sweep file on a resume, read back and validated field by
// field for the report; the status of a run folder from its markers; the run table as
// `confpack sweep --list` prints it.
#include <fmt/format.h>

#include <algorithm>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/input_document.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "core/settings_table.hpp"
#include "study/sweep.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json runTableJson(const std::vector<SweepRun>& runs) {
  json table = json::array();
  const std::vector<std::string> varied = variedSettings(runs);
  for (const SweepRun& r : runs) {
    json cfg;
    core::to_json(cfg, r.config);
    table.push_back({{"name", r.name}, {"deposit", r.depositName()}, {"label", r.label(varied)}, {"config", cfg}});
  }
  return table;
}

}  // namespace

std::string_view toString(RunStatus s) {
  switch (s) {
    case RunStatus::Pending:
      return "pending";
    case RunStatus::Incomplete:
      return "incomplete";
    case RunStatus::Failed:
      return "failed";
    case RunStatus::Done:
      return "done";
  }
  return "?";
}

RunStatus runStatus(const fs::path& runDir) {
  if (fs::exists(runDir / kDoneMarker)) return RunStatus::Done;
  if (fs::exists(runDir / kFailedMarker)) return RunStatus::Failed;
  if (fs::exists(runDir)) return RunStatus::Incomplete;
  return RunStatus::Pending;
}

void prepareSweepDir(const fs::path& dir, const SweepSpec& spec, const std::vector<SweepRun>& runs) {
  fs::create_directories(dir / "runs");
  fs::create_directories(dir / "deposits");
  const json table = runTableJson(runs);
  const fs::path tablePath = dir / kSweepTable;
  if (fs::exists(tablePath)) {
    const json existing = core::readJsonFile(tablePath, "sweep table");
    // Run by run, each stored configuration as the reader reads it, so that a table written by an
    // earlier version in another spelling (mu_w as box.wall_friction) still resumes; nothing of
    // the stored document is copied (a hand-edited value may be nested too deep for that).
    const auto sameRun = [](const json& stored, const json& expected) {
      if (!stored.is_object() || stored.size() != expected.size()) return false;
      for (const auto& [key, value] : expected.items()) {
        if (!stored.contains(key)) return false;
        if (key != "config") {
          if (stored.at(key) != value) return false;
          continue;
        }
        try {
          if (json(stored.at(key).get<core::RunConfig>()) != value) return false;
        } catch (const std::exception&) {
          return false;
        }
      }
      return true;
    };
    const auto sameTable = [&](const json& stored) {
      if (!stored.is_array() || stored.size() != table.size()) return false;
      for (std::size_t i = 0; i < table.size(); ++i)
        if (!sameRun(stored[i], table[i])) return false;
      return true;
    };
    if (!existing.contains("runs") || !sameTable(existing.at("runs")))
      throw std::invalid_argument(
          fmt::format("{}: holds a different sweep (its run table differs from this sweep file's); resume it with the "
                      "sweep file that made it, or choose a new output folder",
                      dir.string()));
    return;
  }
  // Several tasks of a job array may get here at once: each writes the same bytes atomically.
  core::writeFileAtomically(tablePath, runTableDocument(spec, runs).dump(1));
}

json runTableDocument(const SweepSpec& spec, const std::vector<SweepRun>& runs) {
  return {{"format", kSweepTableFormat},
          {"version", 1},
          {"name", spec.name},
          {"sweep", spec.source},
          {"runs", runTableJson(runs)}};
}

namespace {

// A run folder's name: letters, digits, '_' or '-', at most 64 of them (it must stay one folder of
// runs/), and no other run's.
std::string readRunName(const core::ObjectReader& row, std::set<std::string>& names) {
  const json& name = row.at("name");
  const std::string text = name.is_string() ? name.get<std::string>() : std::string();
  if (text.empty() || text.size() > 64 ||
      text.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") != std::string::npos)
    row.refuse("name", fmt::format("expected a run folder's name: letters, digits, '_' or '-' (got {})",
                                   core::jsonExcerpt(name)));
  if (!names.insert(text).second) row.refuse("name", fmt::format("\"{}\" names two runs", text));
  return text;
}

// "d" and the index of a deposit below `runCount`.
std::size_t readDepositIndex(const core::ObjectReader& row, std::size_t runCount) {
  const json& deposit = row.at("deposit");
  const std::string dep = deposit.is_string() ? deposit.get<std::string>() : std::string();
  if (dep.size() < 2 || dep.size() > 10 || dep[0] != 'd' ||
      dep.find_first_not_of("0123456789", 1) != std::string::npos || std::stoul(dep.substr(1)) >= runCount)
    row.refuse("deposit", fmt::format("expected \"d\" and the index of a deposit below the number of runs (got {})",
                                      core::jsonExcerpt(deposit)));
  return static_cast<std::size_t>(std::stoul(dep.substr(1)));
}

// Row `index` of the table: a user may edit it, so every field is checked.
SweepRun readRun(const json& r, std::size_t index, std::size_t runCount, std::set<std::string>& names,
                 std::string_view source) {
  const core::ObjectReader row(r, source, fmt::format("runs[{}]", index));
  row.onlyKeys({"name", "deposit", "label", "config"});
  for (const char* key : {"name", "deposit", "config"}) (void)row.at(key);
  SweepRun run;
  run.index = index;
  run.name = readRunName(row, names);
  run.depositIndex = readDepositIndex(row, runCount);
  try {
    core::from_json(row.at("config"), run.config);
    run.config.validate();
  } catch (const std::invalid_argument& e) {
    row.refuse("config", e.what());
  } catch (const json::exception& e) {
    row.refuse("config", e.what());
  }
  return run;
}

}  // namespace

std::vector<SweepRun> parseRunTable(const json& doc, std::string_view source, SweepSpec* spec) {
  const core::ObjectReader top =
      core::readDocument(doc, source, {kSweepTableFormat, 1, core::HeaderKey::Required, core::HeaderKey::Optional},
                         {"format", "version", "name", "sweep", "runs"});
  const json& table = top.array("runs");
  const json& sweep = top.at("sweep", "the sweep file that made the table");
  // The table on disk was listed already, under whatever --max-runs its sweep was given.
  SweepSpec parsed = parseSweepSpec(sweep, fmt::format("{}: sweep", source), std::max(kDefaultMaxRuns, table.size()));
  std::vector<SweepRun> runs;
  std::set<std::string> names;
  for (const json& r : table) runs.push_back(readRun(r, runs.size(), table.size(), names, source));
  if (spec) *spec = std::move(parsed);
  return runs;
}

std::vector<SweepRun> readRunTable(const fs::path& dir, SweepSpec* spec) {
  const fs::path tablePath = dir / kSweepTable;
  if (!fs::exists(tablePath))
    throw std::invalid_argument(fmt::format("{}: not a sweep folder (no {})", dir.string(), kSweepTable));
  return parseRunTable(core::readJsonFile(tablePath, "sweep table"), tablePath.string(), spec);
}

std::string formatRunTable(const std::vector<SweepRun>& runs, const fs::path& dir, std::optional<std::size_t> taskIndex,
                           std::size_t taskCount) {
  std::set<std::size_t> slice;
  if (taskIndex)
    for (std::size_t i : sliceRuns(runs, *taskIndex, taskCount)) slice.insert(i);
  // A column per varied setting, as wide as its name or its widest value.
  const std::vector<std::string> varied = variedSettings(runs);
  const std::vector<std::string> names = settingNames(varied);
  std::vector<std::vector<std::string>> cells(runs.size());
  std::vector<std::size_t> widths;
  for (const std::string& n : names) widths.push_back(n.size());
  for (std::size_t k = 0; k < runs.size() && !varied.empty(); ++k) {
    json cfg;
    core::to_json(cfg, runs[k].config);
    for (std::size_t i = 0; i < varied.size(); ++i) {
      cells[k].push_back(settingText(cfg, varied[i]));
      widths[i] = std::max(widths[i], cells[k].back().size());
    }
  }
  std::ostringstream out;
  out << fmt::format("{:<7} {:<7} {:<6} {:>5} {:>8} {:>5} {:>6} {:<7}", "run", "deposit", "family", "x_S", "W", "mu_w",
                     "seed", "backend");
  for (std::size_t i = 0; i < names.size(); ++i) out << fmt::format(" {:<{}}", names[i], widths[i]);
  out << (dir.empty() ? "" : " status") << '\n';
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const SweepRun& r = runs[k];
    if (taskIndex && !slice.count(r.index)) continue;
    const std::string w = r.config.box.periodicY ? fmt::format("bi{}", core::numberText(r.config.box.width))
                                                 : core::numberText(r.config.box.width);
    out << fmt::format("{:<7} {:<7} {:<6} {:>5} {:>8} {:>5} {:>6} {:<7}", r.name, r.depositName(), familyName(r.config),
                       core::numberText(r.config.population.smallFraction), w,
                       core::numberText(r.config.walls.friction), r.config.seed, r.config.backend);
    for (std::size_t i = 0; i < varied.size(); ++i) out << fmt::format(" {:<{}}", cells[k][i], widths[i]);
    if (!dir.empty()) out << ' ' << toString(runStatus(dir / "runs" / r.name));
    out << '\n';
  }
  return out.str();
}

}  // namespace confpack::study
