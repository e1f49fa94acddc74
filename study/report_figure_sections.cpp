// The report's figure sections after the fits (study/report_figure_sections.hpp).
#include "study/report_figure_sections.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "study/csv_table.hpp"
#include "study/report_relaxation.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

void addSettingSections(Document& doc, const StudyView& study, FigureWriter& figures) {
  const std::vector<std::pair<std::string, std::string>> quantities = {{"solid_fraction", "phi"},
                                                                       {"coordination/Z", "Z"}};
  for (std::size_t i = 0; i < study.settings.size(); ++i) {
    const bool numeric = std::all_of(study.groups.begin(), study.groups.end(),
                                     [&](const auto& g) { return g.first.settings[i].number.has_value(); });
    if (!numeric) continue;
    const std::string& name = study.settingNames[i];
    std::string stem;
    for (char c : name) stem += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    bool headed = false;
    for (const auto& [key, symbol] : quantities) {
      if (!study.keys.count(key)) continue;
      if (!headed) {
        doc.heading(2, fmt::format("Solid fraction and coordination against {}", name));
        doc.paragraph(fmt::format(
            "{} is a setting of the run configuration this study varies. Each point is a configuration's mean over "
            "its replicas with the standard error of that mean; each line joins the configurations that differ in "
            "{} alone: solid for the first {}, dashed for the second.",
            study.settings[i], name, study.compared.noun));
        headed = true;
      }
      Plot p{fmt::format("{}_vs_{}", symbol, stem),
             fmt::format("{} against {}", symbol, name),
             name,
             symbol,
             {},
             {},
             false};
      // One line per (configuration without this setting, backend), in the study's order.
      std::map<std::pair<ConfKey, std::string>, Series> lines;
      std::map<ConfKey, int> colors;
      for (const auto& [k, _] : study.groups) {
        ConfKey rest = k;
        rest.settings.erase(rest.settings.begin() + static_cast<std::ptrdiff_t>(i));
        if (!colors.count(rest)) colors.emplace(rest, static_cast<int>(colors.size()) + 1);
        for (std::size_t bi = 0; bi < study.sides.size(); ++bi) {
          const ReplicaStat st = study.statOf(k, study.sides[bi], key);
          if (st.n == 0) continue;
          Series& line = lines[{rest, study.sides[bi]}];
          if (line.name.empty())
            line = Series{fmt::format("{} W={} {}", seriesText(seriesOf(rest)), widthText(rest), study.sides[bi]),
                          colors.at(rest),
                          bi > 0,
                          true,
                          {}};
          line.points.push_back({*k.settings[i].number, st.mean, standardError(st)});
        }
      }
      for (auto& [_, line] : lines) p.series.push_back(std::move(line));
      doc.figure(figures.draw(p));
    }
  }
}

namespace {

// ---------------------------------------------------------------------------------------------
// Profiles written by the runs (study/csv_table.hpp), averaged over replicas

// Column-wise mean over replicas whose profiles share the abscissa; otherwise the first replica.
CsvTable averageProfiles(const std::vector<CsvTable>& tables) {
  const CsvTable& first = tables.front();
  std::vector<const CsvTable*> same;
  for (const CsvTable& t : tables) {
    bool ok = t.columns == first.columns && t.rows.size() == first.rows.size();
    for (std::size_t i = 0; ok && i < t.rows.size(); ++i) ok = std::abs(t.rows[i][0] - first.rows[i][0]) < 1e-9;
    if (ok) same.push_back(&t);
  }
  CsvTable out = first;
  for (std::size_t i = 0; i < out.rows.size(); ++i)
    for (std::size_t c = 1; c < out.columns.size(); ++c) {
      double s = 0.0;
      for (const CsvTable* t : same) s += t->rows[i][c];
      out.rows[i][c] = s / static_cast<double>(same.size());
    }
  return out;
}

// visit(k, color, side index, runs) for each configuration k of series sk and each side with runs
// there: one line of a figure each, the configuration's colour (1, 2, ... in the series) shared
// by its sides.
template <class Visit>
void forEachLine(const StudyView& study, const SeriesKey& sk, const Visit& visit) {
  int color = 0;
  for (const auto& [k, bySide] : study.groups) {
    if (seriesOf(k) != sk) continue;
    ++color;
    for (std::size_t bi = 0; bi < study.sides.size(); ++bi)
      if (bySide.count(study.sides[bi])) visit(k, color, bi, bySide.at(study.sides[bi]));
  }
}

// The figures of one profile file the runs wrote (CSV), averaged over replicas: one figure per
// series and column, the configurations of the series as lines. figureIndex numbers the figures.
void addProfileFigures(Document& doc, const StudyView& study, FigureWriter& figures, const std::string& name,
                       int& figureIndex) {
  const std::string base = fs::path(name).stem().string();
  for (const SeriesKey& sk : study.seriesKeys()) {
    std::map<std::string, std::vector<Series>> byColumn;
    std::vector<std::string> columnOrder;
    std::string xLabel;
    forEachLine(study, sk, [&](const ConfKey& k, int color, std::size_t bi, const std::vector<const RunRecord*>& runs) {
      std::vector<CsvTable> tables;
      for (const RunRecord* r : runs)
        if (r->status == RunStatus::Done)
          if (auto t = readCsv(study.runDir(*r) / name)) tables.push_back(std::move(*t));
      if (tables.empty()) return;
      const CsvTable avg = averageProfiles(tables);
      xLabel = avg.columns[0];
      // At most four value columns per profile keep the figures readable.
      for (std::size_t c = 1; c < avg.columns.size() && c <= 4; ++c) {
        if (!byColumn.count(avg.columns[c])) columnOrder.push_back(avg.columns[c]);
        Series s{fmt::format("W={} {} (n={})", widthText(k), study.sides[bi], tables.size()), color, bi > 0, true, {}};
        s.markers = false;
        for (const auto& row : avg.rows)
          if (std::isfinite(row[c])) s.points.push_back({row[0], row[c], 0.0});
        byColumn[avg.columns[c]].push_back(std::move(s));
      }
    });
    for (const std::string& col : columnOrder) {
      Plot p{fmt::format("profile_{:03d}_{}", ++figureIndex, base),
             fmt::format("{}: {} for {}", base, col, seriesText(sk)),
             xLabel,
             col,
             byColumn[col],
             {},
             false};
      doc.figure(figures.draw(p));
    }
  }
}

// A profile file the runs write (analysis/analyze.hpp, writeProfiles) as its section names and
// defines it.
struct ProfileKind {
  std::string file, title, definition;
};

// In the order of the report: phi(y) first.
const std::vector<ProfileKind>& profileKinds() {
  static const std::vector<ProfileKind> k = {
      {"phi_y.csv", "Solid-fraction profiles phi(y)",
       "phi(y) is the solid fraction of thin slices of the bulk region parallel to the side walls, at a distance y "
       "(in d_L) from a wall, averaged over the two walls so that it runs from a wall to mid-gap (raw y when "
       "biperiodic)."},
      {"z_y.csv", "Coordination profiles Z(y)",
       "Z(y) is the number of grain-grain contacts per bulk grain in slices 0.25 d_L thick at a distance y from the "
       "nearer wall, in total and per contact type (simple, double, triple)."},
      {"homogeneity_y.csv", "Fractions of large and small grains across the gap, P_L(y) and P_S(y)",
       "P_L and P_S are the shares of large and of small grains among the bulk grains whose centre is in a layer "
       "1 d_L thick, along y from wall to wall."},
      {"homogeneity_z.csv", "Fractions of large and small grains with height, P_L(z) and P_S(z)",
       "P_L and P_S are the shares of large and of small grains among the grains whose centre is in a layer "
       "1 d_L thick, along z from the floor."},
      {"orientation_cos.csv", "Contact orientations against the vertical",
       "The density (mean 1) of the force-carrying contacts' normals against |n_z| = cos theta, theta the angle "
       "to the vertical, in total and per contact type; 1 everywhere for isotropic contacts."},
      {"orientation_azimuth.csv", "Contact orientations in azimuth",
       "The density (mean 1) of the force-carrying contacts' normals against their azimuth folded to [0, 180) "
       "degrees, in total and per contact type; 1 everywhere for isotropic contacts."},
  };
  return k;
}

}  // namespace

void addProfileSections(Document& doc, const StudyView& study, FigureWriter& figures) {
  std::vector<ProfileKind> shown;
  for (const ProfileKind& k : profileKinds())
    if (study.csvNames.count(k.file)) shown.push_back(k);
  for (const std::string& name : study.csvNames)
    if (std::none_of(shown.begin(), shown.end(), [&](const ProfileKind& k) { return k.file == name; }))
      shown.push_back({name, "Profile " + name, "A profile the runs wrote as " + name + "."});
  int figureIndex = 0;
  for (const ProfileKind& k : shown) {
    doc.heading(2, k.title);
    doc.paragraph(k.definition + " Each line is a width, averaged over its replicas: solid for the first " +
                  study.compared.noun + ", dashed for the second.");
    addProfileFigures(doc, study, figures, k.file, figureIndex);
  }
}

void addRelaxationSections(Document& doc, const StudyView& study, FigureWriter& figures) {
  std::vector<RelaxationFamily> families;
  for (const SeriesKey& sk : study.seriesKeys()) {
    RelaxationFamily family{familyName(sk), fmt::format("relaxation_{:02d}", families.size() + 1), {}};
    forEachLine(study, sk, [&](const ConfKey& k, int color, std::size_t bi, const std::vector<const RunRecord*>& runs) {
      RelaxationLine line{{}, color, bi > 0, {}};
      for (const RunRecord* r : runs)
        if (r->status == RunStatus::Done && r->result.contains("timing") && r->result["timing"].contains("history"))
          line.histories.push_back(r->result["timing"]["history"]);
      if (line.histories.empty()) return;
      line.label = fmt::format("W={} {} (n={})", widthText(k), study.sides[bi], line.histories.size());
      family.lines.push_back(std::move(line));
    });
    families.push_back(std::move(family));
  }
  addRelaxationSection(doc, figures, families, study.compared.noun);
}

}  // namespace confpack::study
