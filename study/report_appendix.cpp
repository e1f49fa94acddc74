// The report's closing sections: runs, tables, cost and method (study/report_appendix.hpp).
#include "study/report_appendix.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/settings_table.hpp"
#include "study/csv_table.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------
// Tables: which result keys go in which tables/FILE.csv (in the order of docs/model.md's
// measurements); a key of none goes to tables/other.csv.

struct TableGroup {
  std::string file;                   // tables/FILE.csv
  std::string what;                   // what its keys measure, as the page lists it
  std::vector<std::string> prefixes;  // key starts with one of these
};

const std::vector<TableGroup>& tableGroups() {
  static const std::vector<TableGroup> g = {
      {"solid_fraction",
       "solid fraction, bulk region, free surface",
       {"solid_fraction", "bulk_region", "free_surface"}},
      {"profile_fit", "fit of the profile phi(y)", {"profile_fit"}},
      {"coordination",
       "coordination, hyperstaticity, wall contacts, rigidity (self-stresses, mechanisms)",
       {"coordination", "hyperstaticity", "wall_contacts", "rigidity"}},
      {"interpenetration", "interpenetration, % by volume", {"interpenetration"}},
      {"homogeneity", "homogeneity", {"homogeneity"}},
      {"order", "anisotropy, fabric, nematic order, orientations", {"anisotropy", "fabric", "nematic", "orientation"}},
      {"equilibrium", "equilibrium residuals", {"equilibrium"}},
      {"cost", "wall time, steps, solver iterations", {"timing", "deposit"}},
      {"other", "every other quantity", {}},
  };
  return g;
}

std::size_t tableGroupOf(const std::string& key) {
  for (std::size_t i = 0; i + 1 < tableGroups().size(); ++i)
    for (const auto& p : tableGroups()[i].prefixes)
      if (key.rfind(p, 0) == 0) return i;
  return tableGroups().size() - 1;
}

// `target` as a '/'-separated path relative to the report folder `reportDir`, or absolute when there
// is none. The report is written into a staging folder beside its final place, in the same parent
// (StagedOutput, apps/cli_common.hpp), so the path still holds once the folder is moved there.
std::string relativeLink(const fs::path& target, const fs::path& reportDir) {
  std::error_code ec;
  const fs::path rel = fs::relative(target, reportDir, ec);
  return (ec || rel.empty() ? fs::absolute(target) : rel).generic_string();
}

}  // namespace

void addRunsSection(Document& doc, const StudyView& study, const fs::path& reportDir, bool runLinks) {
  doc.heading(2, "Runs");
  std::vector<std::vector<std::string>> problems;
  std::vector<std::vector<std::string>> others;
  for (const RunRecord& r : study.records) {
    const auto value = [&](const std::string& k, const char* f) -> std::string {
      const auto it = r.values.find(k);
      if (it == r.values.end() || !it->second) return "";
      return fmt::format(fmt::runtime(f), *it->second);
    };
    std::string status(toString(r.status));
    std::string note;
    if (r.status == RunStatus::Failed) note = r.marker.is_object() ? r.marker.value("error", "") : "";
    if (unequilibrated(r)) {
      status = "done, NOT equilibrated";
      // A quasi-static run that is not at rest has used all its finisher steps.
      const auto finisher = r.values.find("timing/stages/quasi_static/steps");
      note = finisher != r.values.end() && finisher->second
                 ? fmt::format("finisher not at rest after {:.0f} steps", *finisher->second)
                 : "stopped at the time limit";
    }
    if (r.status == RunStatus::Pending || r.status == RunStatus::Incomplete) note = "missing: not run or interrupted";
    std::vector<std::string> row = {runLinks ? link(r.run.name, relativeLink(study.runDir(r), reportDir)) : r.run.name,
                                    r.run.label(study.runSettings),
                                    status,
                                    value("solid_fraction", "{:.4f}"),
                                    value("timing/wall_s", "{:.1f}"),
                                    note};
    (r.status != RunStatus::Done || !note.empty() ? problems : others).push_back(std::move(row));
  }
  const char* names =
      runLinks ? "Each name links to the run's folder." : "The run folders are not part of this report.";
  if (problems.empty())
    doc.paragraph(fmt::format("Every run finished and reached equilibrium. {}", names));
  else
    doc.paragraph(fmt::format(
        "{} runs are missing, failed or did not reach equilibrium: they come first, with why. Missing and failed "
        "runs are absent from the fits and tables{}; unequilibrated runs are included. {}",
        problems.size(),
        study.standIns.empty() ? "" : " (where their configuration's values stand in, the introduction says so)",
        names));
  problems.insert(problems.end(), std::make_move_iterator(others.begin()), std::make_move_iterator(others.end()));
  doc.table({"run", "configuration", "status", "phi", "wall [s]", "note"}, problems);
}

namespace {

// A number of a table file: full precision, so that reading it back gives the same double.
std::string exact(double v) {
  return fmt::format("{:.17g}", v);
}

// The CSV of one table group: a row per (quantity, configuration), per backend the mean, the
// sample standard deviation and the number of replicas that finished, and the difference of the
// first two backends with its uncertainty. Empty cells: no value (std and the uncertainty need
// two replicas).
void writeQuantityTable(const fs::path& path, const StudyView& study, const std::vector<std::string>& keys) {
  std::vector<std::string> head = {"key", "family", "x_S", "W", "mu_w", "biperiodic"};
  for (const std::string& path : study.settings) head.push_back(path);  // the varied settings, by path
  for (const auto& b : study.sides)
    for (const char* what : {"_mean", "_std", "_n"}) head.push_back(b + what);
  const std::string diffName = study.pair() ? study.sides[0] + "_minus_" + study.sides[1] : "";
  if (study.pair()) {
    head.push_back(diffName);
    head.push_back(diffName + "_uncertainty");
  }
  std::vector<std::vector<std::string>> rows;
  for (const std::string& key : keys)
    for (const auto& [k, _] : study.groups) {
      std::vector<std::string> row = {key,         familyOf(k.shape, k.xs), exact(k.xs), exact(k.width),
                                      exact(k.mu), k.periodic ? "1" : "0"};
      for (const SettingValue& v : k.settings) row.push_back(v.text);
      std::vector<ReplicaStat> stats;
      for (const auto& b : study.sides) {
        const ReplicaStat& st = stats.emplace_back(study.statOf(k, b, key));
        row.push_back(st.n ? exact(st.mean) : "");
        row.push_back(st.n >= 2 ? exact(st.std) : "");
        row.push_back(std::to_string(st.n));
      }
      if (study.pair()) {
        const bool both = stats[0].n && stats[1].n;
        const BackendDifference d = backendDifference(stats[0], stats[1]);
        row.push_back(both ? exact(d.value) : "");
        row.push_back(both && d.uncertainty ? exact(*d.uncertainty) : "");
      }
      rows.push_back(std::move(row));
    }
  writeCsv(path, head, rows);
}

}  // namespace

void addQuantityTables(Document& doc, const StudyView& study, const fs::path& reportDir) {
  std::vector<std::vector<std::string>> groupKeys(tableGroups().size());
  std::vector<std::string> notApplicable;
  for (const std::string& k : study.keys) (study.applies(k) ? groupKeys[tableGroupOf(k)] : notApplicable).push_back(k);
  std::string files;
  for (std::size_t g = 0; g < tableGroups().size(); ++g) {
    if (groupKeys[g].empty()) continue;
    const std::string file = "tables/" + tableGroups()[g].file + ".csv";
    fs::create_directories(reportDir / "tables");
    writeQuantityTable(reportDir / file, study, groupKeys[g]);
    files += fmt::format("{}{} ({})", files.empty() ? "" : ", ", link(file, file), tableGroups()[g].what);
  }
  doc.heading(2, "Tables");
  if (files.empty()) {
    doc.paragraph("No run of this study has finished: there is no quantity to tabulate.");
    return;
  }
  std::string varied;
  for (const std::string& path : study.settings) varied += ", " + path;
  std::string text = fmt::format(
      "Every quantity of result.json per configuration: {}. One row per quantity (key) and configuration (family, "
      "x_S, W, mu_w, biperiodic 1 or 0{}); per {} the mean, the sample standard deviation and the number n of "
      "replicas that finished",
      files, varied, study.compared.noun);
  if (study.pair())
    text += fmt::format(", then {} − {} with its uncertainty sqrt(s1²/n1 + s2²/n2)", study.sides[0], study.sides[1]);
  text += "; full precision.";
  if (!notApplicable.empty()) {
    std::string list;
    for (const auto& k : notApplicable) list += (list.empty() ? "" : ", ") + k;
    text += " Not applicable to any run of this study (null in every result.json): " + list + ".";
  }
  doc.paragraph(text);
}

void addCostSection(Document& doc, const StudyView& study) {
  doc.heading(2, "Cost");
  std::vector<std::vector<std::string>> rows;
  for (const std::string& b : study.sides) {
    std::vector<double> wall, steps, perStep;
    const auto collect = [](const RunRecord& r, const std::string& key, std::vector<double>& into) {
      const auto it = r.values.find(key);
      if (it != r.values.end() && it->second) into.push_back(*it->second);
    };
    for (const RunRecord& r : study.records) {
      if (r.status != RunStatus::Done || study.sideOf(r) != b) continue;
      collect(r, "timing/wall_s", wall);
      collect(r, "timing/steps", steps);
      collect(r, "timing/iterations_per_step", perStep);
    }
    const auto mean = [](const std::vector<double>& v, const char* f) {
      return v.empty() ? std::string("-") : fmt::format(fmt::runtime(f), replicaStat(v).mean);
    };
    double total = 0.0;
    for (double w : wall) total += w;
    rows.push_back({b, std::to_string(wall.size()), wall.empty() ? "-" : fmt::format("{:.0f}", total),
                    mean(wall, "{:.1f}"), mean(steps, "{:.0f}"), mean(perStep, "{:.3g}")});
  }
  const bool timed = std::any_of(study.keys.begin(), study.keys.end(),
                                 [](const std::string& k) { return tableGroups()[tableGroupOf(k)].file == "cost"; });
  doc.paragraph(fmt::format("Compaction per {} over its finished runs (wall time in seconds)", study.compared.noun) +
                (timed ? "; every timing quantity per configuration is in tables/cost.csv." : "."));
  doc.table({study.compared.column, "finished runs", "total wall [s]", "mean wall per run [s]", "mean steps",
             "mean solver iterations per step"},
            rows);
}

namespace {

// "confpack 0.1.0 at revision abc (12 runs); ..." over the finished runs, in the order first met
// (results written before confpack recorded its revision say "revision not recorded").
std::string runBuilds(const StudyView& study) {
  std::vector<std::pair<std::string, std::size_t>> builds;
  for (const RunRecord& r : study.records) {
    if (r.status != RunStatus::Done) continue;
    const auto text = [&](const char* key) {  // a hand-edited result may hold anything there
      const auto it = r.result.is_object() ? r.result.find(key) : r.result.end();
      return it != r.result.end() && it->is_string() ? it->get<std::string>() : std::string();
    };
    const std::string version = text("confpack_version");
    const std::string revision = text("confpack_revision");
    const std::string build = version.empty()    ? "a build that recorded no version"
                              : revision.empty() ? fmt::format("confpack {} (revision not recorded)", version)
                                                 : fmt::format("confpack {} at revision {}", version, revision);
    auto it = std::find_if(builds.begin(), builds.end(), [&](const auto& b) { return b.first == build; });
    if (it == builds.end())
      builds.emplace_back(build, 1);
    else
      ++it->second;
  }
  std::string out;
  for (std::size_t i = 0; i < builds.size(); ++i)
    out += fmt::format("{}{} ({} run{})", i == 0 ? "" : "; ", builds[i].first, builds[i].second,
                       builds[i].second == 1 ? "" : "s");
  return out;
}

// The runs' boxes: L_x and h, and where a grain cap shortened some (docs/model.md, "Box"), which
// configurations and to what length.
std::string boxSentence(const StudyView& study) {
  if (study.records.empty()) return "";
  double longest = 0.0;
  std::size_t cap = 0;
  std::set<double> heights;
  for (const RunRecord& r : study.records) {
    longest = std::max(longest, r.run.config.box.lengthX);
    heights.insert(r.run.config.box.height);
    cap = std::max(cap, r.run.config.deposition.grainCap);
  }
  std::map<std::string, double> shortened;  // "BSP xS=40 W=20" (the run's label to its mu_w) -> L_x
  for (const RunRecord& r : study.records)
    if (r.run.config.box.lengthX < longest) {
      const std::string label = r.run.label();
      shortened[label.substr(0, label.find(" mu="))] = r.run.config.box.lengthX;
    }
  std::string text = fmt::format("Boxes L_x x W x h with h = {:g} d_L (the target height) and L_x = {:g} d_L",
                                 fmt::join(heights, ", "), longest);
  if (shortened.empty()) return text + ".";
  text += fmt::format(
      ", but where a box would hold more than {} grains (deposition.grain_cap), shortened along x to hold about "
      "that many:",
      cap);
  for (const auto& [label, length] : shortened) text += fmt::format(" {} L_x = {};", label, core::numberText(length));
  text.back() = '.';
  return text;
}

}  // namespace

void addMethodSection(Document& doc, const StudyView& study, bool runLinks) {
  doc.heading(2, "Method");
  const std::string builds = runBuilds(study);
  doc.bullets({
      boxSentence(study),
      "The finished runs were computed by " +
          (builds.empty() ? std::string("no build yet (no run finished)") : builds) +
          ". A run resumed from a checkpoint records the build that finished it.",
      "The study is defined in " +
          (runLinks ? (study.sweepDir / "sweep.json").string() : "sweep.json of the sweep folder " + sweepName(study)) +
          "; each run's resolved configuration and result are in its folder (config.json, result.json).",
      "Means and standard deviations are over the replicas (seeds) that finished; missing and failed runs are "
      "excluded, unequilibrated ones included and flagged in the run table.",
      "Fits of the geometrical model (docs/model.md): linear least squares in 1/W over the confined widths, "
      "weighted by the replicas' standard errors of the mean when every width has two or more differing replicas, "
      "unweighted otherwise; the biperiodic value is a check of the fitted bulk value.",
      fmt::format(
          "{} differences are first minus second {}; (*) marks a difference larger than twice its "
          "uncertainty.{} Units: lengths in large-grain diameters d_L, times in sqrt(d_L/g), wall time in "
          "seconds.",
          capitalized(study.compared.column), study.compared.noun,
          study.compared.backend() ? " Both backends of one (configuration, seed) compact the same deposit." : ""),
  });
}

}  // namespace confpack::study
