#pragma once
// The report's fits of the geometrical model (docs/model.md): phi(W) = phi_bulk - C/W and
// Z(W) = Z_bulk - C_Z/W per series and side over the confined widths, weighted by the replicas'
// standard errors of the mean; their sections (the figure against d_L/W, the table of the fits and
// the two sides' differences), and the samples lambda_L is read from (study/report_lambda.hpp),
// which take C from the phi(W) fit. The parts of study/report.cpp share it.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometric_model.hpp"
#include "study/report_document.hpp"
#include "study/report_figures.hpp"
#include "study/report_lambda.hpp"
#include "study/report_study.hpp"

namespace confpack::study {

// An unweighted line through two widths passes through both points: its parameters have no
// standard error (a weighted one takes theirs from the replicas' errors).
bool fitErrorsKnown(const analysis::ConfinementFit& f);

// The fitted parameters as the fit section and the summary both print them, so the two agree.
std::string bulkText(const analysis::ConfinementFit& f);
std::string cText(const analysis::ConfinementFit& f);
std::string chiText(const analysis::ConfinementFit& f);
std::string qText(const analysis::ConfinementFit& f);

// A fit of the geometrical model, per series and side (the backend unless --compare names another).
struct FitRow {
  SeriesKey series;
  std::string side;
  std::optional<analysis::ConfinementFit> fit;
  std::string why;                            // when no fit
  std::vector<std::array<double, 3>> points;  // 1/W, mean, sigma
  std::optional<ReplicaStat> biperiodic;
};

/// The fits of the geometrical model a report shows, made once and read by the summary and the
/// fit sections alike (empty when the study has no such quantity).
struct ConfinementFits {
  std::vector<FitRow> phi;  ///< solid_fraction
  std::vector<FitRow> z;    ///< coordination/Z
};

// The fits of one quantity of result.json (`key`) per series and side, over the confined widths.
std::vector<FitRow> confinementFits(const StudyView& study, const std::string& key);

// The families' samples for lambda_L (study/report_lambda.hpp): per series and backend, the
// replicas' phi(y) at the confined width nearest `target`, and C of the series' phi(W) fit.
std::vector<LambdaSample> lambdaSamples(const StudyView& study, const std::vector<FitRow>& phiFits, double target);

// Each sample's replicas read instead from the first of `sources` (sweep folders, e.g. more seeds of
// one family run apart) that has finished runs of its series and backend at its width, and fitted
// again; checkLambdaSources() has checked that those runs are the study's configurations. Returns
// the sources that gave no sample.
std::vector<std::filesystem::path> readLambdaSources(std::vector<LambdaSample>& samples,
                                                     const std::vector<std::filesystem::path>& sources);

// The figures of the phi(W) and Z(W) fits and of lambda_L, in this order.
void addFitFigureSections(Document& doc, const StudyView& study, FigureWriter& figures, const ConfinementFits& fits,
                          References& references);

}  // namespace confpack::study
