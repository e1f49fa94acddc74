#include "study/report_lambda.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "core/settings_table.hpp"
#include "study/csv_table.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

std::optional<double> lambdaWidth(const std::vector<double>& widths, double target) {
  std::optional<double> best;
  for (double w : widths) {
    if (!best) {
      best = w;
      continue;
    }
    const double d = std::abs(w - target), bestD = std::abs(*best - target);
    if (d < bestD || (d == bestD && w > *best)) best = w;
  }
  return best;
}

void fitLambdaSample(LambdaSample& s) {
  // Profiles on another grid than their first replica's are runs of another build: the sample
  // is reported as not fitted rather than fitted without some of them.
  analysis::ProfileFitDef def;
  def.bidisperse = s.xs > 0.0;
  try {
    s.fit = analysis::fitAveragedProfile(s.seeds, def);
  } catch (const std::invalid_argument& e) {
    s.fit = analysis::AveragedProfileFit{};
    s.fit.seeds = static_cast<int>(s.seeds.size());
    s.fit.reason = e.what();
  }
}

void fitLambdaSamples(std::vector<LambdaSample>& samples) {
  for (LambdaSample& s : samples) fitLambdaSample(s);
}

namespace {

// "1.23 ± 0.045"
std::string withError(double v, double e) {
  return fmt::format("{:.3g} ± {:.2g}", v, e);
}

std::string lengthText(const analysis::AveragedProfileFit& f, const analysis::FittedLength& l) {
  if (!f.ok) return "no fit";
  if (!l.determined) return "not determined";
  return withError(l.value, l.error);
}

// The samples of one backend that have a lambda_L.
std::vector<const LambdaSample*> fitted(const std::vector<LambdaSample>& samples, const std::string& backend) {
  std::vector<const LambdaSample*> out;
  for (const LambdaSample& s : samples)
    if (s.backend == backend && s.fit.ok && s.fit.lambdaL.determined) out.push_back(&s);
  return out;
}

std::vector<std::string> backendsOf(const std::vector<LambdaSample>& samples) {
  std::vector<std::string> out;
  for (const LambdaSample& s : samples)
    if (std::find(out.begin(), out.end(), s.backend) == out.end()) out.push_back(s.backend);
  return out;
}

// The walls' friction of the x_S line: the pinacoids' (the finding compares them at the same
// mu_w), else the least the spheres have.
std::optional<double> lineFriction(const std::vector<const LambdaSample*>& samples) {
  std::optional<double> mu;
  for (const LambdaSample* s : samples)
    if (!s->sphere && s->plain) return s->mu;
  for (const LambdaSample* s : samples)
    if (s->sphere && s->plain && (!mu || s->mu < *mu)) mu = s->mu;
  return mu;
}

// Spheres of the x_S line, in x_S order.
std::vector<const LambdaSample*> xsLine(const std::vector<const LambdaSample*>& samples) {
  std::vector<const LambdaSample*> out;
  const std::optional<double> mu = lineFriction(samples);
  for (const LambdaSample* s : samples)
    if (s->sphere && s->plain && mu && s->mu == *mu) out.push_back(s);
  std::sort(out.begin(), out.end(), [](const LambdaSample* a, const LambdaSample* b) { return a->xs < b->xs; });
  return out;
}

std::optional<analysis::LineFit> lineOf(const std::vector<double>& x, const std::vector<double>& y,
                                        const std::vector<double>& sigma) {
  if (x.size() < 2) return std::nullopt;
  try {
    return analysis::fitLine(x, y, sigma);
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // all at one x
  }
}

std::string qualityText(const analysis::LineFit& f) {
  if (f.dof == 0) return "2 points: the line is not tested";
  return fmt::format("chi²/dof {:.2g}, Q {:.2g}", f.chiSquare / f.dof, f.quality.value_or(0.0));
}

// "falls" / "rises" / "shows no trend": a slope beyond twice its error either way.
std::string trend(double slope, double error, const char* falls, const char* rises, const char* none) {
  if (slope + 2.0 * error < 0.0) return falls;
  if (slope - 2.0 * error > 0.0) return rises;
  return none;
}

struct XsLine {
  std::vector<const LambdaSample*> points;
  std::optional<analysis::LineFit> fit;
};

XsLine xsLineFit(const std::vector<const LambdaSample*>& samples) {
  XsLine out{xsLine(samples), std::nullopt};
  std::vector<double> x, y, e;
  for (const LambdaSample* s : out.points) {
    x.push_back(s->xs);
    y.push_back(s->fit.lambdaLOverDAvg.value);
    e.push_back(s->fit.lambdaLOverDAvg.error);
  }
  out.fit = lineOf(x, y, e);
  return out;
}

struct CLine {
  std::vector<const LambdaSample*> points;
  std::optional<analysis::LineFit> fit;
};

// lambda_L against C: weighted by sigma_lambda^2 + b^2 sigma_C^2 (the effective variance of a
// line with errors in x too), b from the fit weighted by sigma_lambda alone.
CLine cLineFit(const std::vector<const LambdaSample*>& samples) {
  CLine out;
  std::vector<double> x, y, e, ec;
  for (const LambdaSample* s : samples)
    if (s->c) {
      out.points.push_back(s);
      x.push_back(*s->c);
      y.push_back(s->fit.lambdaL.value);
      e.push_back(s->fit.lambdaL.error);
      ec.push_back(s->cError.value_or(0.0));
    }
  out.fit = lineOf(x, y, e);
  if (out.fit) {
    std::vector<double> eff(e.size());
    for (std::size_t i = 0; i < e.size(); ++i) eff[i] = std::hypot(e[i], out.fit->slope * ec[i]);
    out.fit = lineOf(x, y, eff);
  }
  return out;
}

const LambdaSample* pinacoidPoint(const std::vector<const LambdaSample*>& samples) {
  for (const LambdaSample* s : samples)
    if (!s->sphere && s->plain) return s;
  return nullptr;
}

const LambdaSample* sphereAt(const std::vector<const LambdaSample*>& samples, double xs, double mu) {
  for (const LambdaSample* s : samples)
    if (s->sphere && s->plain && s->xs == xs && s->mu == mu) return s;
  return nullptr;
}

void writeTable(const fs::path& path, const std::vector<LambdaSample>& samples) {
  const auto exact = [](double v) { return fmt::format("{:.17g}", v); };
  const auto opt = [&](const std::optional<double>& v) { return v ? exact(*v) : std::string(); };
  std::vector<std::vector<std::string>> rows;
  for (const LambdaSample& s : samples) {
    const analysis::AveragedProfileFit& f = s.fit;
    const auto length = [&](const analysis::FittedLength& l, std::vector<std::string>& row) {
      const bool ok = f.ok && l.determined;
      row.push_back(ok ? exact(l.value) : "");
      row.push_back(ok ? exact(l.error) : "");
      row.push_back(ok ? exact(l.covarianceError) : "");
      row.push_back(ok ? opt(l.jackknifeError) : "");
    };
    std::vector<std::string> row = {s.series, s.backend, exact(s.width), std::to_string(f.seeds), f.ok ? "1" : "0"};
    length(f.lambdaL, row);
    length(f.lambdaS, row);
    row.push_back(exact(f.meanSize));
    length(f.lambdaLOverDAvg, row);
    row.push_back(f.ok ? exact(f.fit.law.gamma[0]) : "");
    row.push_back(f.ok ? exact(f.fit.law.phiBulk) : "");
    row.push_back(f.ok ? exact(f.fit.rms) : "");
    row.push_back(opt(s.c));
    row.push_back(opt(s.cError));
    row.push_back(f.ok ? "" : f.reason);
    rows.push_back(std::move(row));
  }
  std::vector<std::string> head = {"series", "backend", "W", "seeds", "ok"};
  for (const char* l : {"lambda_L", "lambda_S"})
    for (const char* what : {"", "_error", "_covariance_error", "_jackknife_error"})
      head.push_back(std::string(l) + what);
  head.push_back("d_avg");
  for (const char* what : {"", "_error", "_covariance_error", "_jackknife_error"})
    head.push_back(std::string("lambda_L_over_d_avg") + what);
  for (const char* c : {"gamma_L", "phi_bulk", "rms_residual", "C", "C_error", "reason"}) head.push_back(c);
  fs::create_directories(path.parent_path());
  writeCsv(path, head, rows);
}

}  // namespace

std::vector<LambdaFinding> lambdaFindings(const std::vector<LambdaSample>& samples) {
  std::vector<LambdaFinding> out;
  for (const std::string& b : backendsOf(samples)) {
    const std::vector<const LambdaSample*> mine = fitted(samples, b);
    // lambda_L / d_avg against x_S.
    const XsLine xs = xsLineFit(mine);
    if (xs.fit) {
      const analysis::LineFit& f = *xs.fit;
      out.push_back({b, fmt::format("{}: lambda_L/d_avg of the spheres (mu_w = {}) {} with x_S: slope {} per 100 % "
                                    "of small grains over x_S = {} to {} ({}). Polydispersity weakening the wall's "
                                    "reach {}.",
                                    b, core::numberText(xs.points.front()->mu),
                                    trend(f.slope, f.slopeError, "falls", "rises", "shows no trend"),
                                    withError(100.0 * f.slope, 100.0 * f.slopeError),
                                    core::numberText(xs.points.front()->xs), core::numberText(xs.points.back()->xs),
                                    qualityText(f), f.slope + 2.0 * f.slopeError < 0.0 ? "holds" : "does not hold")});
    }
    if (const LambdaSample* p = pinacoidPoint(mine))
      if (const LambdaSample* s = sphereAt(mine, p->xs, p->mu)) {
        const double d = p->fit.lambdaLOverDAvg.value - s->fit.lambdaLOverDAvg.value;
        const double e = std::hypot(p->fit.lambdaLOverDAvg.error, s->fit.lambdaLOverDAvg.error);
        out.push_back(
            {b, fmt::format("{}: lambda_L/d_avg is {} for pinacoids against {} for spheres (x_S = {}, mu_w "
                            "= {}), a difference of {}. Smaller for pinacoids than for spheres {}.",
                            b, withError(p->fit.lambdaLOverDAvg.value, p->fit.lambdaLOverDAvg.error),
                            withError(s->fit.lambdaLOverDAvg.value, s->fit.lambdaLOverDAvg.error),
                            core::numberText(p->xs), core::numberText(p->mu), fmt::format("{:+.3g} ± {:.2g}", d, e),
                            d + 2.0 * e < 0.0 ? "holds" : "does not hold")});
      }
    // lambda_L against C.
    const CLine c = cLineFit(mine);
    if (c.fit) {
      const analysis::LineFit& f = *c.fit;
      const bool rises = f.slope - 2.0 * f.slopeError > 0.0;
      const bool linear = f.dof == 0 || f.quality.value_or(0.0) >= 0.01;
      out.push_back({b, fmt::format("{}: over {} families, lambda_L = {} + {} C (lambda_L and C in d_L; {}; "
                                    "Pearson r = {:.2f}). lambda_L correlating linearly with C {}.",
                                    b, c.points.size(), withError(f.intercept, f.interceptError),
                                    withError(f.slope, f.slopeError), qualityText(f), f.correlation,
                                    rises && linear ? "holds"
                                    : rises         ? "does not hold: lambda_L rises with C, but not on a line "
                                                      "within the errors"
                                                    : "does not hold: no significant slope")});
    }
  }
  return out;
}

void addLambdaSection(Document& doc, FigureWriter& figures, const std::vector<LambdaSample>& samples, double target,
                      const fs::path& reportDir, const std::vector<fs::path>& unusedSources) {
  doc.heading(2, "Wall ordering length lambda_L against x_S and against C");
  std::vector<double> widths;
  for (const LambdaSample& s : samples)
    if (std::find(widths.begin(), widths.end(), s.width) == widths.end()) widths.push_back(s.width);
  std::sort(widths.begin(), widths.end());
  std::string widthsText;
  for (double w : widths) widthsText += (widthsText.empty() ? "" : ", ") + core::numberText(w);
  doc.paragraph(fmt::format(
      "lambda_L (lambda_S) is the length, in d_L, over which the layering of the large (small) grains decays away "
      "from a wall: from the fit of phi(y) averaged over the replicas of each family at W = {} d_L ({}; the "
      "nearest width a family has when it lacks that one: read at W = {}). The uncertainty is the larger of the "
      "fit's standard error and the jackknife over the replicas (each left out in turn); d_avg is the mean grain "
      "size. Every number at full precision, with both uncertainties, is in {}.",
      core::numberText(target), "the report's --lambda-width", widthsText,
      link("tables/lambda.csv", "tables/lambda.csv")));
  writeTable(reportDir / "tables" / "lambda.csv", samples);
  std::vector<std::string> read;
  for (const LambdaSample& s : samples)
    if (!s.source.empty())
      read.push_back(fmt::format("{} ({}): its {} replicas from {}", s.family, s.backend, s.fit.seeds, s.source));
  for (const fs::path& dir : unusedSources)
    read.push_back(
        fmt::format("{}: none, it has no finished runs of the study's families at their widths", dir.string()));
  if (!read.empty()) {
    doc.paragraph(
        "Read from other sweep folders (the report's --lambda-from, the study's configurations apart from their "
        "seeds) instead of the study's runs; C stays the study's:");
    doc.bullets(read);
  }
  std::vector<std::vector<std::string>> rows;
  for (const LambdaSample& s : samples) {
    const analysis::AveragedProfileFit& f = s.fit;
    rows.push_back({s.family, s.backend, core::numberText(s.width), std::to_string(f.seeds), lengthText(f, f.lambdaL),
                    s.xs > 0.0 ? lengthText(f, f.lambdaS) : "-", f.ok ? fmt::format("{:.4f}", f.meanSize) : "-",
                    lengthText(f, f.lambdaLOverDAvg), f.ok ? fmt::format("{:.3g}", f.fit.rms) : "-",
                    s.c ? withError(*s.c, s.cError.value_or(0.0)) : "-", f.ok ? "" : f.reason});
  }
  doc.table({"family", "backend", "W", "replicas", "lambda_L [d_L]", "lambda_S [d_L]", "d_avg [d_L]", "lambda_L/d_avg",
             "rms residual", "C [d_L]", "note"},
            rows);

  const std::vector<std::string> backends = backendsOf(samples);
  Plot byXs{"lambdaL_vs_xS",
            "lambda_L/d_avg against x_S (spheres, line; pinacoids, square)",
            "x_S [%]",
            "lambda_L / d_avg",
            {},
            {},
            false};
  Plot byC{"lambdaL_vs_C",
           "lambda_L against C of the phi(W) fit, with the weighted line",
           "C [d_L]",
           "lambda_L [d_L]",
           {},
           {},
           false};
  for (std::size_t bi = 0; bi < backends.size(); ++bi) {
    const std::string& b = backends[bi];
    const int color = static_cast<int>(bi) + 1;
    const std::vector<const LambdaSample*> mine = fitted(samples, b);
    const XsLine xs = xsLineFit(mine);
    if (!xs.points.empty()) {
      Series line{
          fmt::format("spheres mu_w={} {}", core::numberText(xs.points.front()->mu), b), color, bi > 0, false, {}};
      for (const LambdaSample* s : xs.points)
        line.points.push_back({s->xs, s->fit.lambdaLOverDAvg.value, s->fit.lambdaLOverDAvg.error});
      byXs.series.push_back(std::move(line));
      if (xs.fit)
        byXs.functions.push_back(fmt::format("[0:*] {:.10g}+{:.10g}*x lc {} dt {} notitle", xs.fit->intercept,
                                             xs.fit->slope, color, bi > 0 ? 2 : 1));
    }
    if (const LambdaSample* p = pinacoidPoint(mine)) {
      Series point{fmt::format("pinacoids mu_w={} {}", core::numberText(p->mu), b), color, bi > 0, false, {}};
      point.pointType = bi > 0 ? 4 : 5;
      point.points.push_back({p->xs, p->fit.lambdaLOverDAvg.value, p->fit.lambdaLOverDAvg.error});
      byXs.series.push_back(std::move(point));
    }
    const CLine c = cLineFit(mine);
    if (!c.points.empty()) {
      Series pts{b, color, bi > 0, false, {}};
      for (const LambdaSample* s : c.points) pts.points.push_back({*s->c, s->fit.lambdaL.value, s->fit.lambdaL.error});
      byC.series.push_back(std::move(pts));
      if (c.fit)
        byC.functions.push_back(fmt::format("{:.10g}+{:.10g}*x lc {} dt {} notitle", c.fit->intercept, c.fit->slope,
                                            color, bi > 0 ? 2 : 1));
    }
  }
  if (!byXs.series.empty()) doc.figure(figures.draw(byXs));
  if (!byC.series.empty()) doc.figure(figures.draw(byC));
  const std::vector<LambdaFinding> findings = lambdaFindings(samples);
  if (findings.empty()) {
    doc.paragraph("Too few families with a lambda_L to draw a line: the findings are not tested.");
    return;
  }
  doc.paragraph(
      "The lines are weighted least squares (1/sigma², against C with C's error carried through the slope); a "
      "finding holds when its slope (or difference) is beyond twice its standard error, and, against C, the line "
      "fits within the errors (Q >= 0.01):");
  std::vector<std::string> items;
  for (const LambdaFinding& f : findings) items.push_back(f.text);
  doc.bullets(items);
}

}  // namespace confpack::study
