#pragma once
// The answers first (docs/model.md, "The study and its report"): per family and side, the numbers
// the study measured with their standard errors (phi_bulk and C, Z_bulk and C_Z of the fits,
// lambda_L, on one sample the contact types and the nematic order, the interpenetration) and its
// runs at equilibrium; the summary section that shows them, opened by a warning where a family's
// boxes are too small for its numbers to carry their physics. The verdict (study/report_verdict.hpp)
// compares the same numbers. The parts of study/report.cpp share it.
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "study/report_document.hpp"
#include "study/report_fits.hpp"
#include "study/report_lambda.hpp"
#include "study/report_study.hpp"

namespace confpack::study {

// A number of the summary with its standard error (none from a single run or a line through two
// points) as printed.
struct Estimate {
  double value = 0.0;
  std::optional<double> error;
  std::string text;
};

// One quantity of the summary per (family, backend), with its short definition.
struct SummaryQuantity {
  std::string name;
  std::string definition;
  std::map<std::pair<SeriesKey, std::string>, Estimate> values;
};

// Runs of a family and backend: at equilibrium (done, equilibrium/reached true) and in total.
struct RunCount {
  std::size_t equilibrated = 0, unequilibrated = 0, done = 0, failed = 0, total = 0;
};

// What the summary and the verdict show, from the same fits as the fit sections.
struct StudySummary {
  std::vector<SummaryQuantity> quantities;
  std::map<std::pair<SeriesKey, std::string>, RunCount> runs;
  std::map<std::pair<SeriesKey, std::string>, std::string> phiFitQuality;  // chi²/dof and Q, or why no fit
  std::vector<LambdaFinding> lambdaFindings;  // the wall-ordering length's two findings, tested
};

// The summary's numbers, from the fits the fit sections show and from the lambda_L samples.
StudySummary summarize(const StudyView& study, const ConfinementFits& fits, const std::vector<LambdaSample>& lambdas);

// The section "Summary: the results per family and backend" (or the compared setting's value).
void addSummarySection(Document& doc, const StudyView& study, const StudySummary& summary, References& references);

}  // namespace confpack::study
