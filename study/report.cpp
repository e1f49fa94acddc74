// The study report's page (study/report.hpp): writeReport reads the study (study/report_study.hpp)
// and fills the document section by section in the order of the page: the introduction here, then
// the summary and the verdict (report_summary, report_verdict), the fits (report_fits), lambda_L
// (report_lambda), the other figures (report_figure_sections), and the runs, the tables, the cost
// and the method (report_appendix). Also the replicas' statistics of report.hpp.
#include "study/report.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <map>
#include <stdexcept>

#include "core/build_info.hpp"
#include "core/packing_io.hpp"
#include "core/run_config.hpp"
#include "study/report_appendix.hpp"
#include "study/report_compare.hpp"
#include "study/report_document.hpp"
#include "study/report_figure_sections.hpp"
#include "study/report_figures.hpp"
#include "study/report_fits.hpp"
#include "study/report_lambda.hpp"
#include "study/report_study.hpp"
#include "study/report_summary.hpp"
#include "study/report_verdict.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

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
  if (!study.standIns.empty()) {
    std::map<std::string, std::vector<std::string>> bySide;  // side -> "MPP x_S=0 mu_w=0 W=5", in order
    for (const auto& [where, _] : study.standIns)
      bySide[where.second].push_back(fmt::format("{} {}{}", seriesText(seriesOf(where.first)),
                                                 where.first.periodic ? "" : "W=", widthText(where.first)));
    std::string parts;
    for (const auto& [side, confs] : bySide)
      parts += fmt::format("{}{}: {}", parts.empty() ? "" : "; ", side, fmt::join(confs, ", "));
    const std::string source = options.runLinks ? options.tablesFrom.string() : folderName(options.tablesFrom);
    doc.paragraph(fmt::format(
        "Not run here, {} configurations' values are those of the tables in {} (each one's mean, standard "
        "deviation and number of replicas, standing in for its runs in the summary, the verdict, the fits and the "
        "tables; their profiles and figures are not here): {}.",
        study.standIns.size(), source, parts));
  }
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

// A run's configuration as --lambda-from compares it: without its seed and threads.
nlohmann::json comparedConfig(const core::RunConfig& c) {
  nlohmann::json j = c;
  j.erase("seed");
  j.erase("threads");
  return j;
}

}  // namespace

void checkLambdaSources(const fs::path& sweepDir, const std::vector<fs::path>& sources) {
  if (sources.empty()) return;
  std::vector<nlohmann::json> study;
  for (const SweepRun& r : readRunTable(sweepDir)) study.push_back(comparedConfig(r.config));
  for (const fs::path& dir : sources)
    for (const SweepRun& r : readRunTable(dir)) {
      const nlohmann::json mine = comparedConfig(r.config);
      if (std::find(study.begin(), study.end(), mine) != study.end()) continue;
      // Named against the study's first run of the same backend and box, else its first run.
      const auto near = std::find_if(study.begin(), study.end(), [&](const nlohmann::json& c) {
        return c["backend"] == mine["backend"] && c["box"] == mine["box"];
      });
      std::string why = "the study has no runs";
      if (!study.empty()) {  // the first change of the JSON patch from it to this run, "/box/height"
        const nlohmann::json patch = nlohmann::json::diff(near != study.end() ? *near : study.front(), mine);
        why = "first difference: " + patch[0]["path"].get<std::string>().substr(1);
      }
      throw std::invalid_argument(
          fmt::format("--lambda-from {}: run {} ({}) is none of the study's configurations apart from its seed ({})",
                      dir.string(), r.name, r.label(), why));
    }
}

ReportSummary writeReport(const fs::path& sweepDir, const fs::path& outDir, const ReportOptions& options) {
  const StudyView study(sweepDir, options.compare, options.tablesFrom);
  fs::create_directories(outDir);
  FigureWriter figures(outDir / "figures", options.gnuplot, options.figureTimeout);
  ReportSummary summary = countRuns(study);
  summary.standIns = study.standIns.size();

  Document doc(fmt::format("confpack study report: {}", study.spec.name));
  addIntroduction(doc, study, summary, options, figures.available(), figures.problem());
  ConfinementFits fits;
  if (study.keys.count("solid_fraction")) fits.phi = confinementFits(study, "solid_fraction");
  if (study.keys.count("coordination/Z")) fits.z = confinementFits(study, "coordination/Z");
  std::vector<LambdaSample> lambdas = lambdaSamples(study, fits.phi, options.lambdaWidth);
  std::vector<fs::path> unusedSources = readLambdaSources(lambdas, options.lambdaFrom);
  summary.unusedLambdaSources = unusedSources;
  if (!options.runLinks) {  // a published report names the other sweep folders as it names the study's
    for (LambdaSample& l : lambdas)
      if (!l.source.empty()) l.source = folderName(l.source);
    for (fs::path& dir : unusedSources) dir = folderName(dir);
  }
  const StudySummary results = summarize(study, fits, lambdas);
  References references(options.reference);
  addSummarySection(doc, study, results, references);
  addVerdictSection(doc, study, results);
  addFitFigureSections(doc, study, figures, fits, references);
  if (!lambdas.empty()) addLambdaSection(doc, figures, lambdas, options.lambdaWidth, outDir, unusedSources);
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
