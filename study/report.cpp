#include "study/report.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <limits>
#include <set>
#include <stdexcept>

#include "analysis/geometric_model.hpp"
#include "core/build_info.hpp"
#include "core/packing_io.hpp"
#include "core/settings_table.hpp"
#include "study/csv_table.hpp"
#include "study/report_compare.hpp"
#include "study/report_document.hpp"
#include "study/report_figure_sections.hpp"
#include "study/report_figures.hpp"
#include "study/report_fits.hpp"
#include "study/report_lambda.hpp"
#include "study/report_relaxation.hpp"
#include "study/report_study.hpp"
#include "study/report_summary.hpp"
#include "study/report_verdict.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

ReplicaStat replicaStat(const std::vector<double>& values) {
  ReplicaStat s;
  s.n = values.size();
  if (s.n == 0) return s;
  for (double v : values) s.mean += v;
  s.mean /= static_cast<double>(s.n);
  if (s.n < 2) return s;
  double ss = 0.0;
  for (double v : values) ss += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(ss / static_cast<double>(s.n - 1));
  return s;
}

BackendDifference backendDifference(const ReplicaStat& a, const ReplicaStat& b) {
  BackendDifference d;
  d.value = a.mean - b.mean;
  if (a.n >= 2 && b.n >= 2)
    d.uncertainty = std::sqrt(a.std * a.std / static_cast<double>(a.n) + b.std * b.std / static_cast<double>(b.n));
  return d;
}

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

ReportSummary countRuns(const StudyView& study) {
  ReportSummary s;
  for (const RunRecord& r : study.records) {
    if (r.settle) continue;
    ++s.runs;
    if (r.status == RunStatus::Done)
      ++s.done;
    else if (r.status == RunStatus::Failed)
      ++s.failed;
    else
      ++s.missing;
    if (unequilibrated(r)) ++s.unequilibrated;
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// The sections (writeReport calls them in the order of the page: the introduction, the summary and
// the verdict, the figures with their fits, the profiles, the runs, the tables, the cost, the method)

void addIntroduction(Document& doc, const StudyView& study, const ReportSummary& summary, const ReportOptions& options,
                     bool figuresDrawn, const std::string& gnuplotProblem) {
  doc.heading(1, doc.title());
  const std::time_t t = std::time(nullptr);
  char when[32];
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", &tm);
  const std::string folder = options.runLinks ? fs::absolute(study.sweepDir).string()
                                              : sweepName(study) + " (its run folders are not part of this report)";
  doc.paragraph(
      fmt::format("Sweep folder: {}. Written {} by confpack {} (revision {}). {} runs: {} done, {} failed, {} missing "
                  "(not run or interrupted), {} done but not equilibrated.",
                  folder, when, core::version(), core::sourceRevision(), summary.runs, summary.done, summary.failed,
                  summary.missing, summary.unequilibrated));
  if (!study.settings.empty()) {
    std::string varied;
    for (std::size_t i = 0; i < study.settings.size(); ++i)
      varied += fmt::format("{}{}{}", i == 0 ? "" : ", ", study.settings[i],
                            study.settingNames[i] == study.settings[i] ? "" : " (" + study.settingNames[i] + ")");
    doc.paragraph(
        fmt::format("Beyond W, shape, x_S, mu_w, seed and {} this study varies {}: each family below "
                    "is one combination of its values.",
                    study.compared.key, varied));
  }
  const ComparedSetting& by = study.compared;
  if (!by.backend())
    doc.paragraph(
        fmt::format("This report compares the runs by {}: {}, each value a series where a report of the "
                    "backends has nscd and Bullet; its settles, if any, belong to that comparison and are "
                    "left out.",
                    by.key, fmt::join(study.sides, " against ")));
  doc.paragraph(
      fmt::format("The results come first: the summary per family and {} and the two {} compared, then the "
                  "figures with their fits and the profiles; the runs, the tables of every quantity, the cost and the "
                  "method follow.",
                  by.noun, by.plural));
  if (!figuresDrawn)
    doc.paragraph(options.gnuplot.empty()
                      ? "Figures were not drawn (disabled); their CSV data and gnuplot scripts are in figures/."
                      : fmt::format("gnuplot ('{}') {}: figures are not drawn. Their CSV data and gnuplot "
                                    "scripts are in figures/ (install gnuplot-nox and rerun `confpack report`).",
                                    options.gnuplot.string(), gnuplotProblem));
}

// `target` as a '/'-separated path relative to the report folder `reportDir`, or absolute when there
// is none. The report is written into a staging folder beside its final place, in the same parent
// (StagedOutput, apps/cli_common.hpp), so the path still holds once the folder is moved there.

std::string relativeLink(const fs::path& target, const fs::path& reportDir) {
  std::error_code ec;
  const fs::path rel = fs::relative(target, reportDir, ec);
  return (ec || rel.empty() ? fs::absolute(target) : rel).generic_string();
}

// Every run once, the ones missing, failed or not at rest first with why, each name a link to its
// folder in the sweep relative to the report (unless `runLinks` is off).
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
        "runs are absent from the fits and tables; unequilibrated runs are included. {}",
        problems.size(), names));
  problems.insert(problems.end(), std::make_move_iterator(others.begin()), std::make_move_iterator(others.end()));
  doc.table({"run", "configuration", "status", "phi", "wall [s]", "note"}, problems);
}

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

// Every quantity of result.json per configuration, in tables/FILE.csv (one file per table group),
// and the page's paragraph that lists them.
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

// What the study cost per backend; each run's wall time is in the run table.
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

}  // namespace

ReportSummary writeReport(const fs::path& sweepDir, const fs::path& outDir, const ReportOptions& options) {
  const StudyView study(sweepDir, options.compare);
  fs::create_directories(outDir);
  FigureWriter figures(outDir / "figures", options.gnuplot, options.figureTimeout);
  ReportSummary summary = countRuns(study);

  Document doc(fmt::format("confpack study report: {}", study.spec.name));
  addIntroduction(doc, study, summary, options, figures.available(), figures.problem());
  ConfinementFits fits;
  if (study.keys.count("solid_fraction")) fits.phi = confinementFits(study, "solid_fraction");
  if (study.keys.count("coordination/Z")) fits.z = confinementFits(study, "coordination/Z");
  const std::vector<LambdaSample> lambdas = lambdaSamples(study, fits.phi, options.lambdaWidth);
  const StudySummary results = summarize(study, fits, lambdas);
  References references(options.reference);
  addSummarySection(doc, study, results, references);
  addVerdictSection(doc, study, results);
  addFitFigureSections(doc, study, figures, fits, references);
  if (!lambdas.empty()) addLambdaSection(doc, figures, lambdas, options.lambdaWidth, outDir);
  addSettingSections(doc, study, figures);
  addProfileSections(doc, study, figures);
  addRelaxationSections(doc, study, figures);
  addRunsSection(doc, study, outDir, options.runLinks);
  addQuantityTables(doc, study, outDir);
  addCostSection(doc, study);
  addMethodSection(doc, study, options.runLinks);

  summary.figures = figures.count();
  summary.figureErrors = figures.errors();
  summary.gnuplotUsed = figures.available();
  summary.gnuplotProblem = figures.problem();
  summary.markdown = outDir / "report.md";
  summary.html = outDir / "report.html";
  core::writeFileAtomically(summary.markdown, renderMarkdown(doc));
  core::writeFileAtomically(summary.html, renderHtml(doc));
  return summary;
}

}  // namespace confpack::study
