// The study as the report's sections see it (study/report_study.hpp): configurations, series and
// their names, and the view of a sweep folder's runs grouped by them.
#include "study/report_study.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "core/settings_table.hpp"
#include "study/csv_table.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

std::optional<double> knownStandardError(const ReplicaStat& st) {
  if (st.n < 2) return std::nullopt;
  return st.std / std::sqrt(static_cast<double>(st.n));
}

double standardError(const ReplicaStat& st) {
  return knownStandardError(st).value_or(0.0);
}

namespace {

ConfKey confKey(const core::RunConfig& c, const std::vector<std::string>& paths,
                const std::vector<std::string>& names) {
  ConfKey k{static_cast<int>(c.population.shape),
            c.population.smallFraction,
            c.walls.friction,
            {},
            c.box.periodicY,
            c.box.width};
  for (std::size_t i = 0; i < paths.size(); ++i) {
    SettingValue v{names[i], settingText(c, paths[i]), std::nullopt};
    char* end = nullptr;
    const double x = std::strtod(v.text.c_str(), &end);
    if (!v.text.empty() && end == v.text.c_str() + v.text.size() && std::isfinite(x)) v.number = x;
    k.settings.push_back(std::move(v));
  }
  return k;
}

// A report table's cell as a number: NaN when empty or not one (parseCsv).
double cellOf(const CsvTable& t, const std::vector<double>& row, const std::string& column) {
  const auto it = std::find(t.columns.begin(), t.columns.end(), column);
  return it == t.columns.end() ? std::nan("") : row[static_cast<std::size_t>(it - t.columns.begin())];
}

// The tables of a report's tables/ folder (study/report_appendix.cpp writes them): every CSV whose
// header starts with a configuration's columns.
std::vector<CsvTable> reportTables(const fs::path& dir) {
  const std::vector<std::string> lead = {"key", "family", "x_S", "W", "mu_w", "biperiodic"};
  std::vector<CsvTable> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".csv") continue;
    std::optional<CsvTable> t = readCsv(e.path());
    if (t && t->columns.size() > lead.size() && std::equal(lead.begin(), lead.end(), t->columns.begin()))
      out.push_back(std::move(*t));
  }
  return out;
}

// Whether a table row is configuration k: its family, x_S, W, mu_w, box and every varied setting.
bool rowIs(const CsvTable& t, std::size_t i, const ConfKey& k, const std::vector<std::string>& settingPaths) {
  const std::vector<double>& row = t.rows[i];
  if (t.text[i][1] != familyOf(k.shape, k.xs) || row[2] != k.xs || row[3] != k.width || row[4] != k.mu ||
      row[5] != (k.periodic ? 1.0 : 0.0))
    return false;
  for (std::size_t s = 0; s < settingPaths.size(); ++s) {
    const auto it = std::find(t.columns.begin(), t.columns.end(), settingPaths[s]);
    if (it == t.columns.end() || t.text[i][static_cast<std::size_t>(it - t.columns.begin())] != k.settings[s].text)
      return false;
  }
  return true;
}

}  // namespace

void checkTablesSource(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw std::invalid_argument(fmt::format("--tables-from {}: not a folder", dir.string()));
  if (reportTables(dir).empty())
    throw std::invalid_argument(
        fmt::format("--tables-from {}: no report table in it (a CSV of confpack report's tables/ folder, its "
                    "columns key, family, x_S, W, mu_w, biperiodic, then each side's _mean, _std and _n)",
                    dir.string()));
}

SeriesKey seriesOf(const ConfKey& k) {
  return {k.shape, k.xs, k.mu, k.settings};
}

std::string capitalized(std::string name) {
  if (!name.empty()) name[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(name[0])));
  return name;
}

std::string familyOf(int shape, double xs) {
  return fmt::format("{}{}", xs > 0.0 ? "B" : "M", shape == static_cast<int>(core::ShapeKind::Sphere) ? "SP" : "PP");
}

std::string settingsText(const std::vector<SettingValue>& settings, const char* lead, const char* sep) {
  std::string out;
  for (const SettingValue& v : settings) out += fmt::format("{}{}{}{}", lead, v.name, sep, v.text);
  return out;
}

std::string widthText(const ConfKey& k) {
  return k.periodic ? fmt::format("biperiodic ({})", core::numberText(k.width)) : core::numberText(k.width);
}

std::string seriesText(const SeriesKey& s) {
  return fmt::format("{} x_S={} mu_w={}{}", familyOf(s.shape, s.xs), core::numberText(s.xs), core::numberText(s.mu),
                     settingsText(s.settings));
}

std::string familyName(const SeriesKey& s) {
  return fmt::format("{}: {} x_S = {}, mu_w = {}{}", familyOf(s.shape, s.xs),
                     s.shape == static_cast<int>(core::ShapeKind::Sphere) ? "spheres" : "pinacoids",
                     core::numberText(s.xs), core::numberText(s.mu), settingsText(s.settings, ", ", " = "));
}

std::string statText(const ReplicaStat& s) {
  if (s.n == 0) return "missing";
  if (s.n == 1) return fmt::format("{:.4g} (n=1)", s.mean);
  return fmt::format("{:.4g} ± {:.2g} (n={})", s.mean, s.std, s.n);
}

StudyView::StudyView(const fs::path& sweepDir, const std::string& compareKey, const fs::path& tablesFrom)
    : sweepDir(sweepDir), records(loadStudy(sweepDir, &spec)) {
  std::vector<SweepRun> runs;
  for (const RunRecord& r : records)
    if (!r.settle) runs.push_back(r.run);
  if (!compareKey.empty()) compared = compareSetting(compareKey, runs);
  if (!compared.keepsSettles()) std::erase_if(records, [](const RunRecord& r) { return r.settle; });
  runSettings = variedSettings(runs);
  settings = compared.familySettings(runs);
  settingNames = study::settingNames(settings);
  for (const RunRecord& r : records) {
    const std::string& side = recordSides.emplace_back(compared.sideOf(r.run));
    if (std::find(sides.begin(), sides.end(), side) == sides.end()) sides.push_back(side);
    groups[confKey(r.run.config, settings, settingNames)][side].push_back(&r);
    if (r.status != RunStatus::Done) continue;
    for (const auto& [k, v] : r.values) keys.insert(k);
    for (const auto& e : fs::directory_iterator(runDir(r)))
      if (e.path().extension() == ".csv") csvNames.insert(e.path().filename().string());
  }
  if (tablesFrom.empty()) return;
  const std::vector<CsvTable> tables = reportTables(tablesFrom);
  for (const auto& [k, bySide] : groups)
    for (const auto& [side, runs] : bySide) {
      if (std::any_of(runs.begin(), runs.end(), [](const RunRecord* r) { return r->status == RunStatus::Done; }))
        continue;
      std::map<std::string, ReplicaStat> values;
      for (const CsvTable& t : tables)
        for (std::size_t i = 0; i < t.rows.size(); ++i) {
          if (!rowIs(t, i, k, settings)) continue;
          const double n = cellOf(t, t.rows[i], side + "_n"), mean = cellOf(t, t.rows[i], side + "_mean");
          if (!(n >= 1.0) || !std::isfinite(mean)) continue;
          const double sd = cellOf(t, t.rows[i], side + "_std");  // empty below two replicas
          values[t.text[i][0]] = {static_cast<std::size_t>(n), mean, std::isfinite(sd) ? sd : 0.0};
        }
      if (!values.empty()) standIns[{k, side}] = std::move(values);
    }
}

ReplicaStat StudyView::statOf(const ConfKey& k, const std::string& side, const std::string& key) const {
  if (const auto s = standIns.find({k, side}); s != standIns.end()) {
    const auto it = s->second.find(key);
    return it == s->second.end() ? ReplicaStat{} : it->second;
  }
  const auto g = groups.find(k);
  if (g == groups.end() || !g->second.count(side)) return ReplicaStat{};
  std::vector<double> v;
  for (const RunRecord* r : g->second.at(side)) {
    if (r->status != RunStatus::Done) continue;
    const auto it = r->values.find(key);
    if (it != r->values.end() && it->second) v.push_back(*it->second);
  }
  return replicaStat(v);
}

const ConfKey* StudyView::sampleOf(const SeriesKey& sk, const std::string& key) const {
  const ConfKey* sample = nullptr;
  std::size_t sampleSides = 0;
  for (const auto& [k, _] : groups) {
    if (seriesOf(k) != sk) continue;
    const auto withValue = static_cast<std::size_t>(
        std::count_if(sides.begin(), sides.end(), [&](const std::string& b) { return statOf(k, b, key).n > 0; }));
    if (withValue == 0) continue;
    const bool better = !sample || withValue > sampleSides ||
                        (withValue == sampleSides && ((k.periodic && !sample->periodic) ||
                                                      (k.periodic == sample->periodic && k.width > sample->width)));
    if (better) sample = &k, sampleSides = withValue;
  }
  return sample;
}

bool StudyView::applies(const std::string& key) const {
  for (const RunRecord& r : records) {
    const auto it = r.values.find(key);
    if (it != r.values.end() && it->second) return true;
  }
  return false;
}

std::set<SeriesKey> StudyView::seriesKeys() const {
  std::set<SeriesKey> out;
  for (const auto& [k, _] : groups) out.insert(seriesOf(k));
  return out;
}

std::size_t StudyView::standInCount(const SeriesKey& sk, const std::string& side) const {
  return static_cast<std::size_t>(std::count_if(standIns.begin(), standIns.end(), [&](const auto& s) {
    return s.first.second == side && seriesOf(s.first.first) == sk;
  }));
}

bool unequilibrated(const RunRecord& r) {
  const auto it = r.values.find("equilibrium/reached");
  return r.status == RunStatus::Done && it != r.values.end() && it->second && *it->second == 0.0;
}

std::string folderName(const fs::path& dir) {
  return fs::weakly_canonical(fs::absolute(dir)).filename().string();
}

std::string sweepName(const StudyView& study) {
  return folderName(study.sweepDir);
}

}  // namespace confpack::study
