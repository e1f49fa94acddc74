// The report's summary of the results per family and side (study/report_summary.hpp).
#include "study/report_summary.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "core/settings_table.hpp"

namespace confpack::study {

namespace {

// A mean over runs as the summary prints it, to `digits` significant digits: "mean ± SE", or
// "mean (1 run)", which has no standard error.
Estimate replicaEstimate(const ReplicaStat& st, int digits) {
  const std::optional<double> se = knownStandardError(st);
  return {st.mean, se,
          se ? fmt::format("{:.{}g} ± {:.2g}", st.mean, digits, *se) : fmt::format("{:.{}g} (1 run)", st.mean, digits)};
}

// phi_bulk and C (or Z_bulk and C_Z) of the fits of one key; nothing when the study has no fit.
void addFitQuantities(StudySummary& out, const std::vector<FitRow>& fits, const std::string& bulkName,
                      const std::string& bulkDefinition, const std::string& cName, const std::string& cDefinition) {
  SummaryQuantity bulk{bulkName, bulkDefinition, {}}, c{cName, cDefinition, {}};
  for (const FitRow& f : fits)
    if (f.fit) {
      const auto error = [&](double e) { return fitErrorsKnown(*f.fit) ? std::optional(e) : std::nullopt; };
      bulk.values[{f.series, f.side}] = {f.fit->bulk, error(f.fit->bulkError), bulkText(*f.fit)};
      c.values[{f.series, f.side}] = {f.fit->c, error(f.fit->cError), cText(*f.fit)};
    }
  if (bulk.values.empty()) return;
  out.quantities.push_back(std::move(bulk));
  out.quantities.push_back(std::move(c));
}

// What a fit of the summary is worth: chi²/dof and Q when weighted; the residuals when a width had
// no standard error to weigh it; a line through two widths tests no law.
std::string fitQualityText(const FitRow& f) {
  if (!f.fit) return "no fit: " + f.why;
  if (f.fit->dof > 0 && f.fit->weighted) return fmt::format("chi²/dof {}, Q {}", chiText(*f.fit), qText(*f.fit));
  if (f.fit->dof > 0)
    return fmt::format("unweighted (a width without a standard error): residual sum of squares {:.3g}, {} dof",
                       f.fit->chiSquare, f.fit->dof);
  return f.fit->weighted ? "2 widths: the law is not tested (no degree of freedom)"
                         : "exact through 2 widths: no standard errors";
}

}  // namespace

StudySummary summarize(const StudyView& study, const ConfinementFits& fits, const std::vector<LambdaSample>& lambdas) {
  StudySummary out;
  if (!fits.phi.empty()) {
    for (const FitRow& f : fits.phi) out.phiFitQuality[{f.series, f.side}] = fitQualityText(f);
    addFitQuantities(out, fits.phi, "phi_bulk",
                     "solid fraction far from the walls, intercept of phi(W) = phi_bulk − C/W", "C",
                     "loss of solid fraction due to the walls, in d_L: C = 2 h (phi_bulk − phi_BL)");
  }
  addFitQuantities(out, fits.z, "Z_bulk",
                   "coordination number (contacts per grain) far from the walls, intercept of Z(W) = Z_bulk − C_Z/W",
                   "C_Z", "loss of coordination due to the walls, in d_L");
  // lambda_L/d_avg of the seed-averaged profile at the lambda width, as the lambda_L section takes it.
  SummaryQuantity lambda{
      "lambda_L/d_avg",
      "length over which the wall's layering of the large grains decays, in mean grain sizes d_avg, from the fit "
      "of phi(y) averaged over the replicas at the width of the lambda_L section (± the larger of the fit's "
      "standard error and the jackknife over the replicas)",
      {}};
  const auto seriesKeys = study.seriesKeys();  // sk points into it, so it must outlive the loop
  for (const LambdaSample& l : lambdas) {
    const SeriesKey* sk = nullptr;
    for (const SeriesKey& k : seriesKeys)
      if (familyName(k) == l.family) sk = &k;
    if (!sk || !l.fit.ok) continue;
    const analysis::FittedLength& v = l.fit.lambdaLOverDAvg;
    lambda.values[{*sk, l.backend}] = {
        v.value, v.error, fmt::format("{:.3g} ± {:.2g} (W = {})", v.value, v.error, core::numberText(l.width))};
  }
  out.lambdaFindings = lambdaFindings(lambdas);
  if (!lambda.values.empty()) out.quantities.push_back(std::move(lambda));
  // Measured on one sample of each family, the biperiodic one (or, without it, the widest confined
  // one), mean ± standard error over its replicas: phi and Z where the study fits no phi_bulk (a
  // study of the grains' shape in the biperiodic box), the pinacoids' contact types and order.
  struct Measured {
    const char* key;
    const char* name;
    const char* definition;
    bool pinacoidsOnly;
  };
  std::vector<Measured> measured;
  if (fits.phi.empty() ||
      std::none_of(fits.phi.begin(), fits.phi.end(), [](const FitRow& f) { return f.fit.has_value(); })) {
    measured.push_back({"solid_fraction", "phi", "solid fraction of the bulk region", false});
    measured.push_back(
        {"coordination/Z", "Z", "coordination number of the bulk region (grain contacts per grain)", false});
  }
  measured.push_back(
      {"coordination/simple", "Z_s", "pinacoids: simple contacts per grain (vertex-face, edge-edge)", true});
  measured.push_back({"coordination/double", "Z_d", "pinacoids: double contacts per grain (edge-face)", true});
  measured.push_back({"coordination/triple", "Z_t", "pinacoids: triple contacts per grain (face-face)", true});
  measured.push_back({"nematic/bulk", "S", "pinacoids: nematic order Q00^2 of the bulk region (1: aligned)", true});
  for (const Measured& m : measured) {
    SummaryQuantity q{m.name,
                      std::string(m.definition) +
                          ", on the biperiodic sample (or the widest confined one), the same for every " +
                          study.compared.noun + " (of the samples most of them have)",
                      {}};
    for (const SeriesKey& sk : study.seriesKeys()) {
      if (m.pinacoidsOnly && sk.shape != static_cast<int>(core::ShapeKind::Pinacoid)) continue;
      const ConfKey* sample = study.sampleOf(sk, m.key);
      if (!sample) continue;
      for (const std::string& b : study.sides)
        if (const ReplicaStat st = study.statOf(*sample, b, m.key); st.n > 0)
          q.values[{sk, b}] = replicaEstimate(st, 4);
    }
    if (!q.values.empty()) out.quantities.push_back(std::move(q));
  }
  const std::string overlap = "interpenetration_percent/exact";
  SummaryQuantity interpenetration{"interpenetration",
                                   "volume shared by overlapping grains, % of the grains' volume, mean over every "
                                   "finished run of the family (± standard error of the mean)",
                                   {}};
  for (const SeriesKey& sk : study.seriesKeys())
    for (const std::string& b : study.sides) {
      std::vector<double> v;
      RunCount& count = out.runs[{sk, b}];
      for (const auto& [k, bySide] : study.groups) {
        if (seriesOf(k) != sk || !bySide.count(b)) continue;
        for (const RunRecord* r : bySide.at(b)) {
          ++count.total;
          if (r->status == RunStatus::Failed) ++count.failed;
          if (r->status != RunStatus::Done) continue;
          ++count.done;
          const auto reached = r->values.find("equilibrium/reached");
          if (reached != r->values.end() && reached->second && *reached->second != 0.0) ++count.equilibrated;
          if (unequilibrated(*r)) ++count.unequilibrated;
          const auto it = r->values.find(overlap);
          if (it != r->values.end() && it->second) v.push_back(*it->second);
        }
      }
      if (v.empty()) continue;
      interpenetration.values[{sk, b}] = replicaEstimate(replicaStat(v), 3);
    }
  if (!interpenetration.values.empty()) out.quantities.push_back(std::move(interpenetration));
  return out;
}

namespace {

// What a family's numbers can carry (docs/sweeps.md, "The warning's thresholds"): below these sizes
// its phi_bulk and C are a check of the pipeline, not a measurement. Measured on frictionless
// spheres at rest: phi of a bulk region 1 d_L thick (44 grains) scatters by 0.011 from seed to seed,
// as much as C/W at W = 10; from about 4 d_L and a few hundred grains, by a few thousandths.
constexpr double kMinBulkThickness = 4.0;  // [d_L]
constexpr double kMinBulkGrains = 300.0;
// Confined widths spanning at least a factor 3: over less, phi_bulk is an extrapolation in 1/W
// longer than the data it comes from.
constexpr double kMinWidthSpan = 3.0;

// The size of what a family measured: the thinnest bulk region and the fewest bulk grains of any of
// its configurations (each the mean over its finished runs, all backends, and the replicas of the
// values standing in from --tables-from), and the confined widths its fits span.
struct FamilySize {
  double thickness = std::numeric_limits<double>::quiet_NaN();  ///< [d_L]
  double grains = std::numeric_limits<double>::quiet_NaN();
  double widthMin = 0.0, widthMax = 0.0;  ///< confined widths with a finished run [d_L]
  int widths = 0;
};

FamilySize familySize(const StudyView& study, const SeriesKey& sk) {
  FamilySize out;
  for (const auto& [k, bySide] : study.groups) {
    if (seriesOf(k) != sk) continue;
    double thickness = 0.0, grains = 0.0;
    int n = 0;
    bool done = false;
    for (const auto& [side, runs] : bySide) {
      if (study.standIns.count({k, side})) {  // another report's values (--tables-from): its replicas' means
        done = true;
        const ReplicaStat lo = study.statOf(k, side, "bulk_region/z_low"),
                          hi = study.statOf(k, side, "bulk_region/z_high"),
                          g = study.statOf(k, side, "bulk_region/grains");
        if (lo.n == 0 || lo.n != hi.n || lo.n != g.n) continue;
        thickness += static_cast<double>(lo.n) * std::max(0.0, hi.mean - lo.mean);
        grains += static_cast<double>(lo.n) * g.mean;
        n += static_cast<int>(lo.n);
        continue;
      }
      for (const RunRecord* r : runs) {
        if (r->status != RunStatus::Done) continue;
        done = true;
        const auto lo = r->values.find("bulk_region/z_low"), hi = r->values.find("bulk_region/z_high"),
                   g = r->values.find("bulk_region/grains");
        if (lo == r->values.end() || hi == r->values.end() || g == r->values.end() || !lo->second || !hi->second ||
            !g->second)
          continue;
        thickness += std::max(0.0, *hi->second - *lo->second);
        grains += *g->second;
        ++n;
      }
    }
    if (done && !k.periodic) {
      out.widthMin = out.widths == 0 ? k.width : std::min(out.widthMin, k.width);
      out.widthMax = out.widths == 0 ? k.width : std::max(out.widthMax, k.width);
      ++out.widths;
    }
    if (n == 0) continue;
    thickness /= n;
    grains /= n;
    if (!(out.thickness <= thickness)) out.thickness = thickness;
    if (!(out.grains <= grains)) out.grains = grains;
  }
  return out;
}

std::string bulkSizeText(const FamilySize& f) {
  return std::isfinite(f.thickness) ? fmt::format("{:.1f} / {:.0f}", f.thickness, f.grains) : "-";
}

std::string widthSpanText(const FamilySize& f) {
  return f.widths == 0   ? "-"
         : f.widths == 1 ? core::numberText(f.widthMin)
                         : fmt::format("{} to {}", core::numberText(f.widthMin), core::numberText(f.widthMax));
}

// The warning that opens the summary where a family's numbers cannot carry its physics: a bulk too
// thin or too small, fits over too narrow a span of widths, or first-backend runs not at rest.
void addAdequacyWarning(Document& doc, const StudyView& study, const StudySummary& summary) {
  std::vector<std::string> problems;
  for (const SeriesKey& sk : study.seriesKeys()) {
    const FamilySize f = familySize(study, sk);
    std::vector<std::string> why;
    if (std::isfinite(f.thickness) && f.thickness < kMinBulkThickness)
      why.push_back(
          fmt::format("its bulk region is {:.1f} d_L thick (fewer than {:g})", f.thickness, kMinBulkThickness));
    if (std::isfinite(f.grains) && f.grains < kMinBulkGrains)
      why.push_back(fmt::format("it holds {:.0f} grains (fewer than {:g})", f.grains, kMinBulkGrains));
    if (f.widths >= 2 && f.widthMax < kMinWidthSpan * f.widthMin)
      why.push_back(fmt::format("its fits span W = {} to {}, a factor {:.2g} (less than {:g})",
                                core::numberText(f.widthMin), core::numberText(f.widthMax), f.widthMax / f.widthMin,
                                kMinWidthSpan));
    const auto first = summary.runs.find({sk, study.sides.front()});
    if (first != summary.runs.end() && first->second.done > first->second.equilibrated)
      why.push_back(fmt::format("{} of {}'s {} finished runs are not at rest",
                                first->second.done - first->second.equilibrated, study.sides.front(),
                                first->second.done));
    if (!why.empty()) problems.push_back(fmt::format("{}: {}.", familyName(sk), fmt::join(why, "; ")));
  }
  if (problems.empty()) return;
  doc.paragraph(
      "Warning: these numbers cannot carry their physics. For the families below the boxes are too small or "
      "the runs not at rest, so that their phi_bulk, C and Z are a test of the pipeline, not a measurement (the "
      "sizes are each family's least over its configurations). The measured values are in docs/medium.md, from "
      "confpack reproduce --scale medium (or --scale paper).");
  doc.bullets(problems);
}

}  // namespace

void addSummarySection(Document& doc, const StudyView& study, const StudySummary& summary, References& references) {
  doc.heading(2, "Summary: the results per family and " + study.compared.noun);
  addAdequacyWarning(doc, study, summary);
  // The columns: each quantity, its published value beside it when the reference file gives one
  // for a family of the study, the fit quality after C; a published quantity the study has no
  // number for (no Z, no profile fit) still gets its reference column, at the end.
  struct Column {
    enum Kind { Value, Reference, FitQuality } kind;
    const SummaryQuantity* quantity = nullptr;
    std::string referenceKey;
  };
  const auto referenced = [&](const std::string& key) {
    const auto keys = study.seriesKeys();
    return std::any_of(keys.begin(), keys.end(), [&](const SeriesKey& sk) { return references.find(sk, key); });
  };
  std::vector<Column> columns;
  std::vector<std::string> head = {"family", study.compared.column, "runs at equilibrium / total", "bulk d_L / grains",
                                   "widths fitted"};
  std::set<std::string> withReference;
  for (const SummaryQuantity& q : summary.quantities) {
    columns.push_back({Column::Value, &q, ""});
    head.push_back(q.name);
    for (const ReferenceQuantity& rq : referenceQuantities())
      if (rq.name == q.name && referenced(rq.key)) {
        columns.push_back({Column::Reference, nullptr, rq.key});
        head.push_back(q.name + " reference");
        withReference.insert(rq.key);
      }
    if (q.name == "C") {
      columns.push_back({Column::FitQuality, nullptr, ""});
      head.push_back("phi(W) fit quality");
    }
  }
  for (const ReferenceQuantity& rq : referenceQuantities())
    if (!withReference.count(rq.key) && referenced(rq.key)) {
      columns.push_back({Column::Reference, nullptr, rq.key});
      head.push_back(rq.name + " reference");
      withReference.insert(rq.key);
    }
  std::vector<std::vector<std::string>> rows;
  for (const SeriesKey& sk : study.seriesKeys()) {
    const FamilySize size = familySize(study, sk);
    for (const std::string& b : study.sides) {
      const RunCount& n = summary.runs.at({sk, b});
      if (n.total == 0) continue;
      const std::size_t standIns = study.standInCount(sk, b);
      std::vector<std::string> row = {familyName(sk), b,
                                      fmt::format("{} / {}{}", n.equilibrated, n.total,
                                                  standIns ? fmt::format(" ({} widths from tables)", standIns) : ""),
                                      bulkSizeText(size), widthSpanText(size)};
      for (const Column& c : columns) {
        if (c.kind == Column::Value) {
          const auto it = c.quantity->values.find({sk, b});
          row.push_back(it != c.quantity->values.end() ? it->second.text : "-");
        } else if (c.kind == Column::Reference) {
          const ReferenceValue* r = references.find(sk, c.referenceKey);
          row.push_back(r ? references.cell(*r) : "-");
        } else {
          const auto fq = summary.phiFitQuality.find({sk, b});
          row.push_back(fq != summary.phiFitQuality.end() ? fq->second : "-");
        }
      }
      rows.push_back(std::move(row));
    }
  }
  doc.table(head, rows);
  if (references.given()) {
    const ReferenceValues& file = references.values();
    const std::string from =
        fmt::format("{}{}", file.source, file.description.empty() ? "" : " (" + file.description + ")");
    if (references.citations().empty()) {
      doc.paragraph(fmt::format("The reference file {} gives no value for the families of this study.", from));
    } else {
      doc.paragraph(fmt::format("Reference values from {}; [n] in a reference cell is its source:", from));
      std::vector<std::string> sources;
      for (std::size_t i = 0; i < references.citations().size(); ++i)
        sources.push_back(fmt::format("[{}] {}", i + 1, references.citations()[i]));
      doc.bullets(sources);
    }
  }
  std::vector<std::string> definitions = {
      "runs at equilibrium: finished runs whose forces and moments balance (equilibrium reached), out of all the "
      "runs of the family and " +
          study.compared.noun +
          (study.standIns.empty() ? ""
                                  : "; \"widths from tables\": the widths whose values stand in from another "
                                    "report's tables (--tables-from), not from runs of this sweep"),
      "bulk d_L / grains: the thickness of the bulk region (3 d_L from the floor and from the free surface) and the "
      "grains in it, the least over the family's configurations (mean over each one's runs)",
      "widths fitted: the confined widths W the fits phi(W) and Z(W) span"};
  for (const SummaryQuantity& q : summary.quantities) {
    definitions.push_back(q.name + ": " + q.definition);
    if (q.name == "C")
      definitions.push_back(
          "phi(W) fit quality: chi² per degree of freedom of the fit over the confined widths and Q, "
          "the probability of a chi² at least as large if the law holds (weighted fits)");
  }
  if (!withReference.empty())
    definitions.push_back(
        "QUANTITY reference: the published value of the reference file for the family (the entry for its x_S and "
        "mu_w when the file has one), ± its published uncertainty, [n] its source");
  definitions.push_back(
      "± values are standard errors; the fits' are from the least squares (docs/model.md). A value marked (1 run) "
      "comes from a single run and one marked (no SE) from a line through two widths: neither has a standard "
      "error, and the verdict does not judge them");
  doc.bullets(definitions);
  if (!summary.lambdaFindings.empty()) {
    doc.paragraph("The wall-ordering length lambda_L (section \"Wall ordering length\" below):");
    std::vector<std::string> findings;
    for (const LambdaFinding& f : summary.lambdaFindings) findings.push_back(f.text);
    doc.bullets(findings);
  }
}

}  // namespace confpack::study
