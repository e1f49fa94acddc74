// `confpack report SWEEPDIR`: the study report (HTML + Markdown + figures) of a sweep folder,
// written all or nothing like every output (StagedOutput): a failure, Ctrl-C or SIGTERM (which
// also stop a hanging gnuplot) leaves the previous report as it was.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <vector>

#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "study/report.hpp"
#include "study/report_compare.hpp"

namespace confpack::app {

namespace {

struct ReportState {
  std::filesystem::path sweepDir;
  std::filesystem::path out;
  std::filesystem::path gnuplot = "gnuplot";
  std::filesystem::path reference;
  std::string compare;
  bool noFigures = false;
  bool noRunLinks = false;
  double lambdaWidth = study::ReportOptions{}.lambdaWidth;
  std::vector<std::filesystem::path> lambdaFrom;
  std::filesystem::path tablesFrom;
};

void runReportCommand(const ReportState& st) {
  const std::filesystem::path out = st.out.empty() ? st.sweepDir / "report" : st.out;
  std::optional<study::ReferenceValues> reference;
  checkInput("report", [&] {
    const auto runs = study::readRunTable(st.sweepDir);  // refuses a folder that is not a sweep
    if (!st.compare.empty()) study::compareSetting(st.compare, runs);
    if (!st.reference.empty()) reference = study::readReferenceValues(st.reference);
    study::checkLambdaSources(st.sweepDir, st.lambdaFrom);
    if (!st.tablesFrom.empty()) study::checkTablesSource(st.tablesFrom);
    checkOutputTarget(out);
  });
  runWork("report", [&] {
    StagedOutput output(out);
    WorkStep step("writing the report");
    study::ReportOptions o;
    o.gnuplot = st.noFigures ? std::filesystem::path{} : st.gnuplot;
    o.reference = std::move(reference);
    o.runLinks = !st.noRunLinks;
    o.compare = st.compare;
    o.lambdaWidth = st.lambdaWidth;
    o.lambdaFrom = st.lambdaFrom;
    o.tablesFrom = st.tablesFrom;
    const study::ReportSummary s = study::writeReport(st.sweepDir, output.dir(), o);
    step.next("moving the report into place");
    output.commit();
    // A figure gnuplot failed on is said in its place in the report and here; the rest stands.
    for (const std::string& e : s.figureErrors) fmt::print(stderr, "confpack report: {}\n", e);
    for (const std::filesystem::path& dir : s.unusedLambdaSources)
      fmt::print(stderr, "confpack report: --lambda-from {}: no family's replicas at its lambda width, not used\n",
                 dir.string());
    if (!st.tablesFrom.empty() && s.standIns == 0)
      fmt::print(stderr,
                 "confpack report: --tables-from {}: every configuration of the sweep has finished runs of each "
                 "side, or none of the tables' rows is one of them: not used\n",
                 st.tablesFrom.string());
    const std::string drawn =
        !s.gnuplotUsed
            ? (st.noFigures ? " (not drawn: --no-figures)" : fmt::format(" (not drawn: gnuplot {})", s.gnuplotProblem))
        : s.figureErrors.empty() ? ""
                                 : fmt::format(" ({} not drawn, see above)", s.figureErrors.size());
    fmt::print("report: {} runs ({} done, {} failed, {} missing, {} not equilibrated), {} figures{}\n  {}\n  {}\n",
               s.runs, s.done, s.failed, s.missing, s.unequilibrated, s.figures, drawn,
               (out / s.html.filename()).string(), (out / s.markdown.filename()).string());
  });
}

}  // namespace

void registerReport(CLI::App& app) {
  auto st = std::make_shared<ReportState>();
  auto* sub = app.add_subcommand("report",
                                 "Tables and figures of a study, the two backends side by side "
                                 "(writes report.html, report.md and figures/)");
  sub->add_option("sweepdir", st->sweepDir, "Sweep folder (made by confpack sweep or reproduce)")
      ->required()
      ->check(CLI::ExistingDirectory);
  sub->add_option("--out", st->out, "Report folder (default: SWEEPDIR/report)");
  sub->add_option("--gnuplot", st->gnuplot, "gnuplot executable used to draw the SVG figures");
  sub->add_option("--reference", st->reference,
                  "Published values to show beside the study's (JSON, format confpack-reference; "
                  "docs/reference-values.md)");
  sub->add_option("--compare", st->compare,
                  "Setting whose two values to put side by side instead of the backends, by its path in config.json "
                  "(e.g. backend_options.solver); the runs must have exactly two values of it")
      ->type_name("KEY");
  sub->add_flag("--no-figures", st->noFigures, "Write the figure data and scripts but do not run gnuplot");
  sub->add_flag("--no-run-links", st->noRunLinks,
                "Name the runs without links to their folders and the sweep folder by its name alone: a report to "
                "publish without the run folders");
  sub->add_option("--lambda-width", st->lambdaWidth,
                  "Width W [d_L] at which lambda_L is read, from phi(y) averaged over the replicas; a family without "
                  "it is read at its nearest confined width")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option(
         "--lambda-from", st->lambdaFrom,
         "Sweep folder whose runs give a family's lambda_L replicas instead of the study's, e.g. more seeds of "
         "one family run apart (repeatable; its runs must be the study's configurations apart from the seed)")
      ->check(CLI::ExistingDirectory)
      ->allow_extra_args(false)  // one folder an occurrence: the sweep folder may follow
      ->excludes("--compare")    // its replicas are matched by backend
      ->type_name("DIR");
  sub->add_option("--tables-from", st->tablesFrom,
                  "The tables/ folder of another report (e.g. docs/medium/tables) whose values stand in for the "
                  "configurations and backends this sweep has no finished run of, e.g. a study's nscd runs when only "
                  "Bullet's were rerun and settled")
      ->type_name("DIR");
  sub->callback([st] { runReportCommand(*st); });
}

}  // namespace confpack::app
