#pragma once
// The study report (docs/model.md, "The study and its report"): reads a sweep folder and writes one
// self-contained HTML file (figures inlined as SVG) and the same content as Markdown (figures
// linked). It leads with the results: a summary per family (shape, x_S, mu_w) and backend (phi_bulk
// and C of the phi(W) fit, its quality, Z_bulk and C_Z, the interpenetration, the runs at
// equilibrium) and a cross-solver verdict (each of those numbers nscd against Bullet, with the
// combined standard error and whether they differ by more than twice it). Then the figures with
// their fits: phi and Z against d_L/W with the geometrical-model fits phi(W) = phi_bulk - C/W and
// Z(W) = Z_bulk - C_Z/W per backend, lambda_L against x_S and against C, the profiles phi(y) and
// the others the runs wrote. Then every run once (the missing, failed or unequilibrated ones first,
// never dropped silently, each linked to its folder), the list of the tables, the cost and the
// method. A setting the sweep varied by its path (study/sweep.hpp, SettingAxis) is part of every
// family and configuration, and phi and Z are drawn against it when it is a number. Every
// quantity of result.json per configuration (shape, x_S, W, mu_w, varied settings) is not on the page
// but in tables/GROUP.csv: per backend the mean, standard deviation and number of the replicas,
// and the difference of the two backends with its uncertainty, at full precision. With
// ReportOptions::compare the two values of another setting take the backends' place throughout
// (study/report_compare.hpp).
//
// Figures: for each one a CSV with its data, a gnuplot script and, when gnuplot is installed, the
// SVG it makes (gnuplot-nox). Without gnuplot the report says so and keeps the CSV and scripts; a
// figure gnuplot fails on says why in its place (study/report_figures.hpp).
//
// The report is a document (study/report_document.hpp) that one function per section fills and
// that renders to both files.
#include <chrono>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "study/reference_values.hpp"
#include "study/sweep.hpp"

namespace confpack::study {

/// Mean and sample standard deviation of replicas.
struct ReplicaStat {
  std::size_t n = 0;
  double mean = 0.0;
  double std = 0.0;  ///< sample standard deviation (n - 1 in the denominator); 0 when n < 2
};

ReplicaStat replicaStat(const std::vector<double>& values);

/// Difference a - b of two replica means with its uncertainty sqrt(s_a^2/n_a + s_b^2/n_b)
/// (the standard error of a difference of independent means). The uncertainty is undefined
/// (nullopt) when either side has fewer than two replicas.
struct BackendDifference {
  double value = 0.0;
  std::optional<double> uncertainty;
};

BackendDifference backendDifference(const ReplicaStat& a, const ReplicaStat& b);

/// One run as the report sees it.
struct RunRecord {
  SweepRun run;
  RunStatus status = RunStatus::Pending;
  nlohmann::json result;                                ///< result.json (null unless done)
  nlohmann::json marker;                                ///< done.json or failed.json
  std::map<std::string, std::optional<double>> values;  ///< flattened numeric leaves ("coordination/Z")
  bool settle = false;  ///< a table run's settle (RUN/settled/): its second result, not a run of its own
};

/// The backend name under which the report shows a run's settle (RUN/settled/, a sweep's
/// settle_with): "bullet" settled by nscd is "bullet_settled", a third series beside the two.
std::string settledName(const std::string& backend);

/// Reads the run table and every run folder of a sweep; a finished run with a settle
/// (RUN/settled/result.json) adds a record of its own after the table's, its backend
/// settledName(backend) and its name "rNNNN/settled" (its folder under runs/).
std::vector<RunRecord> loadStudy(const std::filesystem::path& sweepDir, SweepSpec* spec = nullptr);

/// Numeric (and boolean, as 0/1) leaves of a result, keyed by their path joined with '/'. Arrays
/// and strings are skipped, and so are objects nested more than 16 deep (a hand-edited file); null
/// leaves are kept as nullopt (a quantity that does not apply).
/// The resolved configuration and the backend settings are not quantities and are skipped.
std::map<std::string, std::optional<double>> flattenResult(const nlohmann::json& result);

struct ReportOptions {
  std::filesystem::path gnuplot = "gnuplot";                            ///< executable; empty = do not draw figures
  std::chrono::milliseconds figureTimeout = std::chrono::seconds(120);  ///< gnuplot is killed after this, per figure
  /// Published values shown next to the study's (`--reference FILE`, study/reference_values.hpp):
  /// a "reference" column beside each quantity of the summary that has one, the citations below
  /// it, and marks at d_L/W = 0 (the law as a dotted line when C is given too) on the phi(W) and
  /// Z(W) figures. None: the report has no reference column.
  std::optional<ReferenceValues> reference;
  /// Each run's name links to its folder, and the sweep folder is named by its path. Off
  /// (`--no-run-links`): names without links and the sweep folder by its name alone, for a report
  /// published without the run folders (the medium study's in docs/).
  bool runLinks = true;
  /// The setting whose two values the report puts side by side (`--compare KEY`, its path in the
  /// run configuration, study/report_compare.hpp): checked to have exactly two values among the
  /// runs, std::invalid_argument otherwise. Empty: the backends, unchecked (a study of one backend
  /// says it has nothing to compare).
  std::string compare;
  /// The width [d_L] at which lambda_L is read (`--lambda-width`), from the phi(y) profile
  /// averaged over the replicas; a family without it is read at its nearest confined width
  /// (study/report_lambda.hpp).
  double lambdaWidth = 10.0;
  /// Sweep folders a family's lambda_L replicas are read from instead of the study's own runs
  /// (`--lambda-from`, e.g. more seeds of one family run apart): the first that has finished runs
  /// of a family and backend at its lambda width gives all of that sample's replicas; C stays the
  /// study's. Checked first by checkLambdaSources(); the backends only (not with `compare`).
  std::vector<std::filesystem::path> lambdaFrom;
  /// A report's tables/ folder (`--tables-from`, e.g. docs/medium/tables of the medium study) whose
  /// values stand in for each configuration and side of the run table that has no finished run
  /// here: a study rerun in part (Bullet's piles settled, nscd's runs left out as the study's) is
  /// judged against the whole study's runs. A stand-in's mean, standard deviation and replica count
  /// enter the summary, the verdict, the fits and the tables as the runs' own would; its runs'
  /// profiles and figures are not there, and the introduction names what stood in. Checked first by
  /// checkTablesSource(). Empty: none.
  std::filesystem::path tablesFrom;
};

/// Refuses (std::invalid_argument naming the folder) a --tables-from folder that holds no table of
/// a report's tables/ folder.
void checkTablesSource(const std::filesystem::path& dir);

/// Refuses (std::invalid_argument naming the folder, its run and the first setting that differs) a
/// --lambda-from folder with a run whose configuration is none of the study's apart from its seed
/// and its threads (which do not change a run's result).
void checkLambdaSources(const std::filesystem::path& sweepDir, const std::vector<std::filesystem::path>& sources);

struct ReportSummary {
  std::size_t runs = 0, done = 0, failed = 0, missing = 0, unequilibrated = 0;
  std::size_t figures = 0;
  std::vector<std::string> figureErrors;  ///< "figure STEM: gnuplot failed: ..." per figure not drawn
  bool gnuplotUsed = false;
  std::string gnuplotProblem;  ///< why a gnuplot asked for was not used (FigureWriter::problem), else empty
  std::vector<std::filesystem::path> unusedLambdaSources;  ///< --lambda-from folders that gave no family's replicas
  std::size_t standIns = 0;  ///< (configuration, side) pairs whose values came from --tables-from
  std::filesystem::path html, markdown;
};

/// Writes report.html, report.md, figures/ (CSV, .gp, .svg) and tables/ (CSV) into outDir. The
/// run links (options.runLinks) are relative to outDir: a staging folder must sit beside the
/// report's final place.
ReportSummary writeReport(const std::filesystem::path& sweepDir, const std::filesystem::path& outDir,
                          const ReportOptions& options = {});

}  // namespace confpack::study
