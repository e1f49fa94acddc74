// The sweep folder on disk (study/sweep.hpp): SWEEPDIR/sweep.json, the run table's document,
// written once and checked against the sweep file on a resume, read back and validated field by
// field for the report; the status of a run folder from its markers; the run table as
// `confpack sweep --list` prints it.
#include <fmt/format.h>

#include <algorithm>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "core/settings_table.hpp"
#include "study/sweep.hpp"
#include "study/sweep_internal.hpp"

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

std::vector<SweepRun> parseRunTable(const json& doc, std::string_view source, SweepSpec* spec) {
  if (!doc.is_object()) bad(source, "(document)", "expected a JSON object");
  for (const auto& [key, v] : doc.items())
    if (key != "format" && key != "version" && key != "name" && key != "sweep" && key != "runs")
      bad(source, core::textExcerpt(key), "unknown key (known: format, version, name, sweep, runs)");
  if (!doc.contains("format") || doc.at("format") != kSweepTableFormat)
    bad(source, "format", fmt::format("not a confpack sweep table (expected \"{}\")", kSweepTableFormat));
  if (doc.contains("version") && doc.at("version") != 1) bad(source, "version", "expected 1");
  if (!doc.contains("runs") || !doc.at("runs").is_array()) bad(source, "runs", "expected an array (the run table)");
  if (!doc.contains("sweep")) bad(source, "sweep", "missing (the sweep file that made the table)");
  const json& table = doc.at("runs");
  // The table on disk was listed already, under whatever --max-runs its sweep was given.
  SweepSpec parsed =
      parseSweepSpec(doc.at("sweep"), fmt::format("{}: sweep", source), std::max(kDefaultMaxRuns, table.size()));
  // A user may edit the table: every field is checked, and a name must stay one folder of runs/.
  std::vector<SweepRun> runs;
  std::set<std::string> names;
  for (const json& r : table) {
    const std::string where = fmt::format("runs[{}]", runs.size());
    if (!r.is_object()) bad(source, where, "expected an object (name, deposit, label, config)");
    for (const auto& [key, v] : r.items())
      if (key != "name" && key != "deposit" && key != "label" && key != "config")
        bad(source, fmt::format("{}.{}", where, core::textExcerpt(key)),
            "unknown key (known: name, deposit, label, config)");
    for (const char* key : {"name", "deposit", "config"})
      if (!r.contains(key)) bad(source, fmt::format("{}.{}", where, key), "missing");
    SweepRun run;
    run.index = runs.size();
    const json& name = r.at("name");
    if (!name.is_string() || name.get<std::string>().empty() || name.get<std::string>().size() > 64 ||
        name.get<std::string>().find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
            std::string::npos)
      bad(source, where + ".name",
          fmt::format("expected a run folder's name: letters, digits, '_' or '-' (got {})", core::jsonExcerpt(name)));
    run.name = name.get<std::string>();
    if (!names.insert(run.name).second) bad(source, where + ".name", fmt::format("\"{}\" names two runs", run.name));
    const json& deposit = r.at("deposit");
    const std::string dep = deposit.is_string() ? deposit.get<std::string>() : std::string();
    if (dep.size() < 2 || dep.size() > 10 || dep[0] != 'd' ||
        dep.find_first_not_of("0123456789", 1) != std::string::npos || std::stoul(dep.substr(1)) >= table.size())
      bad(source, where + ".deposit",
          fmt::format("expected \"d\" and the index of a deposit below the number of runs (got {})",
                      core::jsonExcerpt(deposit)));
    run.depositIndex = static_cast<std::size_t>(std::stoul(dep.substr(1)));
    try {
      core::from_json(r.at("config"), run.config);
      run.config.validate();
    } catch (const std::invalid_argument& e) {
      bad(source, where + ".config", e.what());
    } catch (const json::exception& e) {
      bad(source, where + ".config", e.what());
    }
    runs.push_back(std::move(run));
  }
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
