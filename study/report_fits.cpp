// The report's fits of the geometrical model, their sections and the lambda_L samples
// (study/report_fits.hpp).
#include "study/report_fits.hpp"

#include <fmt/format.h>

#include <cmath>
#include <exception>
#include <map>

#include "study/csv_table.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

bool fitErrorsKnown(const analysis::ConfinementFit& f) {
  return f.weighted || f.dof > 0;
}

std::string bulkText(const analysis::ConfinementFit& f) {
  return fitErrorsKnown(f) ? fmt::format("{:.4f} ± {:.2g}", f.bulk, f.bulkError)
                           : fmt::format("{:.4f} (no SE)", f.bulk);
}
std::string cText(const analysis::ConfinementFit& f) {
  return fitErrorsKnown(f) ? fmt::format("{:.3f} ± {:.2g}", f.c, f.cError) : fmt::format("{:.3f} (no SE)", f.c);
}
std::string chiText(const analysis::ConfinementFit& f) {
  return f.dof > 0 ? fmt::format("{:.3g}/{}", f.chiSquare, f.dof) : "exact (2 points)";
}
std::string qText(const analysis::ConfinementFit& f) {
  return f.quality ? fmt::format("{:.3g}", *f.quality) : "-";
}

std::vector<FitRow> confinementFits(const StudyView& study, const std::string& key) {
  std::vector<FitRow> out;
  for (const SeriesKey& s : study.seriesKeys())
    for (const auto& b : study.sides) {
      FitRow row{s, b, std::nullopt, "", {}, std::nullopt};
      std::vector<double> w, v, sigma;
      bool weighted = true;
      for (const auto& [k, _] : study.groups) {
        if (seriesOf(k) != s) continue;
        const ReplicaStat st = study.statOf(k, b, key);
        if (st.n == 0) continue;
        if (k.periodic) {
          row.biperiodic = st;
          continue;
        }
        w.push_back(k.width);
        v.push_back(st.mean);
        // The replicas' standard error of the mean weighs each width; with a single replica
        // (or identical values) there is none and the fit is unweighted.
        const double se = standardError(st);
        sigma.push_back(se);
        weighted = weighted && se > 0.0;
        row.points.push_back({1.0 / k.width, st.mean, se});
      }
      if (w.size() >= 2) {
        try {
          row.fit = analysis::fitConfinement(w, v, weighted ? sigma : std::vector<double>{});
        } catch (const std::exception& e) {
          row.why = e.what();
        }
      } else {
        row.why = fmt::format("{} confined width{} with data: need 2", w.size(), w.size() == 1 ? "" : "s");
      }
      if (!row.points.empty() || row.biperiodic) out.push_back(std::move(row));
    }
  return out;
}

namespace {

// A quantity fitted with the geometrical model quantity(W) = quantity_bulk - cName/W, as its
// section names and defines it.
struct FitQuantity {
  std::string quantity, cName, stem;
  std::string title, definition;
};

// The values against d_L/W with the fitted lines, the biperiodic value at d_L/W = 0: one colour per
// series, solid for the first backend, dashed for the second.
void addFitFigure(Document& doc, const StudyView& study, FigureWriter& figures, const std::vector<FitRow>& fits,
                  const FitQuantity& q, References& references) {
  std::string caption =
      fmt::format("{} against d_L/W with the fits {}_bulk - {}/W (biperiodic at 0)", q.quantity, q.quantity, q.cName);
  Plot p{q.stem, caption, "d_L / W", q.quantity, {}, {}, true};
  int color = 0;
  std::map<SeriesKey, int> colors;
  for (const FitRow& f : fits) {
    if (!colors.count(f.series)) colors[f.series] = ++color;
    const bool dashed = f.side != study.sides[0];
    Series s{fmt::format("{} {}", seriesText(f.series), f.side), colors[f.series], dashed, false, f.points};
    if (f.biperiodic)
      s.points.insert(s.points.begin(),
                      {0.0, f.biperiodic->mean,
                       f.biperiodic->n >= 2 ? f.biperiodic->std / std::sqrt(double(f.biperiodic->n)) : 0.0});
    p.series.push_back(std::move(s));
    if (f.fit)
      p.functions.push_back(fmt::format("[0:*] {:.10g} - {:.10g}*x lc {} dt {} notitle", f.fit->bulk, f.fit->c,
                                        colors[f.series], dashed ? 2 : 1));
  }
  // The published bulk value of each series as a square at d_L/W = 0, in the series' colour, and
  // with a published C the published law as a dotted line.
  bool marked = false;
  for (const auto& [series, color] : colors) {
    const ReferenceValue* bulk = references.find(series, q.quantity + "_bulk");
    if (!bulk) continue;
    marked = true;
    Series s{fmt::format("reference {} [{}]", seriesText(series), references.number(bulk->citation)),
             color,
             false,
             false,
             {{0.0, bulk->value, bulk->uncertainty}}};
    s.pointType = 5;
    p.series.push_back(std::move(s));
    if (const ReferenceValue* c = references.find(series, q.cName))
      p.functions.push_back(fmt::format("[0:*] {:.10g} - {:.10g}*x lc {} dt 3 notitle", bulk->value, c->value, color));
  }
  if (marked) p.caption += "; squares: reference values";
  doc.figure(figures.draw(p));
}

// The figure of quantity(W) = quantity_bulk - cName/W against d_L/W with the fitted lines, the
// fit table and the backends' differences of its parameters.
void addFitSection(Document& doc, const StudyView& study, FigureWriter& figures, const std::vector<FitRow>& fits,
                   const FitQuantity& q, References& references) {
  if (fits.empty()) return;
  const std::string& quantity = q.quantity;
  const std::string& cName = q.cName;
  doc.heading(2, q.title);
  doc.paragraph(q.definition);
  addFitFigure(doc, study, figures, fits, q, references);
  doc.paragraph(
      fmt::format("The fit per series (shape, x_S, mu_w) and {} over the confined widths:", study.compared.noun));
  std::vector<std::vector<std::string>> rows;
  for (const FitRow& f : fits) {
    std::vector<std::string> row = {seriesText(f.series), f.side, std::to_string(f.points.size())};
    if (f.fit) {
      row.push_back(bulkText(*f.fit));
      row.push_back(cText(*f.fit));
      row.push_back(fmt::format("{:.3f}", f.fit->zeta()));
      row.push_back(f.fit->weighted ? "weighted" : "unweighted");
      row.push_back(chiText(*f.fit));
      row.push_back(qText(*f.fit));
    } else {
      for (int i = 0; i < 5; ++i) row.push_back(i == 0 ? "no fit: " + f.why : "");
    }
    row.push_back(f.biperiodic ? statText(*f.biperiodic) : "-");
    rows.push_back(std::move(row));
  }
  doc.table({"series", study.compared.column, "widths", quantity + "_bulk", cName + " [d_L]",
             "zeta = " + cName + "/" + quantity + "_bulk", "weights", "chi²/dof", "Q", "biperiodic"},
            rows);
  // Backend differences of the fitted parameters.
  if (study.pair()) {
    std::vector<std::vector<std::string>> diffs;
    for (const FitRow& a : fits) {
      if (a.side != study.sides[0] || !a.fit) continue;
      for (const FitRow& b : fits)
        if (b.side == study.sides[1] && b.series == a.series && b.fit) {
          const bool known = fitErrorsKnown(*a.fit) && fitErrorsKnown(*b.fit);
          const auto difference = [&](double va, double vb, double ea, double eb, int decimals) {
            return known ? fmt::format("{:+.{}f} ± {:.2g}", va - vb, decimals, std::hypot(ea, eb))
                         : fmt::format("{:+.{}f} (no SE)", va - vb, decimals);
          };
          diffs.push_back({seriesText(a.series),
                           difference(a.fit->bulk, b.fit->bulk, a.fit->bulkError, b.fit->bulkError, 4),
                           difference(a.fit->c, b.fit->c, a.fit->cError, b.fit->cError, 3)});
        }
    }
    if (!diffs.empty()) {
      doc.paragraph(
          fmt::format("{} differences of the fitted parameters ({} − {}, uncertainty from the two "
                      "fits' standard errors):",
                      capitalized(study.compared.column), study.sides[0], study.sides[1]));
      doc.table({"series", quantity + "_bulk", cName}, diffs);
    }
  }
}

// The phi(y) profiles and mean grain sizes of the finished runs of series `sk` and `side` at the
// confined width `width`.
std::vector<analysis::SeedProfile> seedProfiles(const StudyView& study, const SeriesKey& sk, const std::string& side,
                                                double width) {
  std::vector<analysis::SeedProfile> out;
  for (const auto& [k, bySide] : study.groups) {
    if (seriesOf(k) != sk || k.periodic || k.width != width) continue;
    const auto runs = bySide.find(side);
    if (runs == bySide.end()) continue;
    for (const RunRecord* r : runs->second) {
      if (r->status != RunStatus::Done) continue;
      const auto table = readCsv(study.runDir(*r) / "phi_y.csv");
      const auto size = r->values.find("mean_size");
      if (!table || table->columns.size() < 2 || size == r->values.end() || !size->second) continue;
      analysis::SeedProfile p;
      for (const auto& row : table->rows) {
        p.y.push_back(row[0]);
        p.phi.push_back(row[1]);
      }
      p.meanSize = *size->second;
      out.push_back(std::move(p));
    }
  }
  return out;
}

}  // namespace

std::vector<LambdaSample> lambdaSamples(const StudyView& study, const std::vector<FitRow>& phiFits, double target) {
  std::vector<LambdaSample> out;
  for (const SeriesKey& sk : study.seriesKeys())
    for (std::size_t bi = 0; bi < study.sides.size(); ++bi) {
      const std::string& b = study.sides[bi];
      std::vector<double> widths;
      for (const auto& [k, bySide] : study.groups)
        if (seriesOf(k) == sk && !k.periodic && bySide.count(b) && study.statOf(k, b, "mean_size").n > 0)
          widths.push_back(k.width);
      const std::optional<double> width = lambdaWidth(widths, target);
      if (!width) continue;
      LambdaSample s;
      s.family = familyName(sk);
      s.series = seriesText(sk);
      s.sphere = sk.shape == static_cast<int>(core::ShapeKind::Sphere);
      s.xs = sk.xs;
      s.mu = sk.mu;
      s.plain = sk.settings.empty();
      s.backend = b;
      s.backendIndex = static_cast<int>(bi);
      s.width = *width;
      s.seeds = seedProfiles(study, sk, b, *width);
      if (s.seeds.empty()) continue;
      for (const FitRow& f : phiFits)
        if (f.series == sk && f.side == b && f.fit) {
          s.c = f.fit->c;
          if (fitErrorsKnown(*f.fit)) s.cError = f.fit->cError;
        }
      out.push_back(std::move(s));
    }
  fitLambdaSamples(out);
  return out;
}

void addFitFigureSections(Document& doc, const StudyView& study, FigureWriter& figures, const ConfinementFits& fits,
                          References& references) {
  addFitSection(doc, study, figures, fits.phi,
                {"phi", "C", "phi_vs_invW", "Solid fraction phi against d_L/W",
                 "The solid fraction phi is the share of the bulk region's volume (away from the floor and the free "
                 "surface) filled by grains; the geometrical model phi(W) = phi_bulk − C/W splits it into phi_bulk, "
                 "its value far from the walls, and C, the loss due to the two wall layers, in d_L."},
                references);
  addFitSection(doc, study, figures, fits.z,
                {"Z", "C_Z", "Z_vs_invW", "Coordination number Z against d_L/W",
                 "The coordination number Z is the mean number of grain-grain contacts per grain of the bulk region; "
                 "the same model Z(W) = Z_bulk − C_Z/W gives its value far from the walls, Z_bulk, and its loss "
                 "due to the walls, C_Z, in d_L."},
                references);
}

std::vector<fs::path> readLambdaSources(std::vector<LambdaSample>& samples, const std::vector<fs::path>& sources) {
  std::vector<fs::path> unused;
  for (const fs::path& dir : sources) {
    const StudyView source(dir, "");
    bool used = false;
    for (const SeriesKey& sk : source.seriesKeys())
      for (LambdaSample& s : samples) {
        if (!s.source.empty() || s.series != seriesText(sk)) continue;  // taken by an earlier source
        std::vector<analysis::SeedProfile> seeds = seedProfiles(source, sk, s.backend, s.width);
        if (seeds.empty()) continue;
        s.seeds = std::move(seeds);
        s.source = dir.string();
        fitLambdaSample(s);
        used = true;
      }
    if (!used) unused.push_back(dir);
  }
  return unused;
}

}  // namespace confpack::study
