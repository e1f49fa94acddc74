#pragma once
// The report's wall-ordering length (docs/model.md, "The seed-averaged fit" and "lambda_L across a
// study"): per family (shape, x_S, mu_w, varied settings) and backend, lambda_L and lambda_S of
// the fit of the phi(y) profile averaged over the replicas at one width (analysis/
// profile_average.hpp), with their uncertainties; lambda_L / d_avg against x_S (the spheres' line,
// the pinacoids' point) and lambda_L against C of the phi(W) fit, each with a weighted straight
// line and its quality, and the two findings they test:
// - lambda_L / d_avg falls as x_S rises (a slope below zero by more than twice its standard
//   error), and is smaller for pinacoids than for spheres (by more than twice the combined error);
// - lambda_L rises linearly with C over all families (a slope above zero by more than twice its
//   standard error, and a chi² the line's errors allow, Q >= 0.01).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometric_model.hpp"
#include "analysis/profile_average.hpp"
#include "study/report_document.hpp"
#include "study/report_figures.hpp"

namespace confpack::study {

/// The width the report reads lambda_L at, among the confined `widths` of a family: `target` when
/// it is one of them, otherwise the nearest, a tie going to the wider (its two walls' layers
/// overlap less). None when `widths` is empty.
std::optional<double> lambdaWidth(const std::vector<double>& widths, double target);

/// One family and backend at the width lambda_L is read at, with its replicas' profiles.
struct LambdaSample {
  std::string family;  ///< as the summary names it
  std::string series;  ///< as the tables name it ("MSP x_S=0 mu_w=0")
  bool sphere = true;
  double xs = 0.0;    ///< [%]
  double mu = 0.0;    ///< side walls' friction
  bool plain = true;  ///< no varied setting beyond the named axes: on the x_S figure
  std::string backend;
  int backendIndex = 0;  ///< colour and dashes
  double width = 0.0;    ///< [d_L]
  std::vector<analysis::SeedProfile> seeds;
  std::string source;                ///< the sweep folder the replicas were read from, if not the study (--lambda-from)
  std::optional<double> c, cError;   ///< C of the family's phi(W) fit for this backend [d_L]
  analysis::AveragedProfileFit fit;  ///< filled by fitLambdaSamples
};

/// Fits a sample's averaged profile (bidisperse when x_S > 0), or says in its fit why not.
void fitLambdaSample(LambdaSample& sample);
/// fitLambdaSample of every sample.
void fitLambdaSamples(std::vector<LambdaSample>& samples);

/// A test of one finding for one backend, as the summary and the section state it.
struct LambdaFinding {
  std::string backend;
  std::string text;  ///< the numbers and whether the finding holds
};

/// lambda_L / d_avg against x_S (spheres with the walls' friction of the pinacoids' family, or
/// the least one, and no varied setting), a line per backend, and the pinacoids against the
/// spheres at the same x_S and mu_w; and lambda_L against C over all families, a line per backend.
std::vector<LambdaFinding> lambdaFindings(const std::vector<LambdaSample>& samples);

/// The section: definitions, the table (also tables/lambda.csv under reportDir), the two figures
/// with their lines, and the findings. `target` is the width asked for (ReportOptions); the samples
/// read from another sweep folder are named, and so are the `unusedSources` (--lambda-from
/// folders that had none of the study's samples).
void addLambdaSection(Document& doc, FigureWriter& figures, const std::vector<LambdaSample>& samples, double target,
                      const std::filesystem::path& reportDir,
                      const std::vector<std::filesystem::path>& unusedSources = {});

}  // namespace confpack::study
