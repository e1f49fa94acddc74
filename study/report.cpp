#include "study/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "analysis/geometric_model.hpp"
#include "core/packing_io.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

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

void flattenInto(const json& j, const std::string& path, std::map<std::string, std::optional<double>>& out) {
  if (j.is_object()) {
    for (const auto& [key, v] : j.items()) {
      const std::string here = path.empty() ? key : path + "/" + key;
      if (here == "config" || here == "backend_settings" || here == "seed") continue;
      flattenInto(v, here, out);
    }
  } else if (j.is_number()) {
    out[path] = j.get<double>();
  } else if (j.is_boolean()) {
    out[path] = j.get<bool>() ? 1.0 : 0.0;
  } else if (j.is_null()) {
    out.try_emplace(path, std::nullopt);
  }
}

json readJson(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return nullptr;
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return nullptr;
  }
}

}  // namespace

std::map<std::string, std::optional<double>> flattenResult(const json& result) {
  std::map<std::string, std::optional<double>> out;
  flattenInto(result, "", out);
  return out;
}

std::vector<RunRecord> loadStudy(const fs::path& sweepDir, SweepSpec* spec) {
  std::vector<RunRecord> out;
  for (SweepRun& r : readRunTable(sweepDir, spec)) {
    RunRecord rec;
    const fs::path dir = sweepDir / "runs" / r.name;
    rec.status = runStatus(dir);
    if (rec.status == RunStatus::Done) {
      rec.marker = readJson(dir / kDoneMarker);
      rec.result = readJson(dir / "result.json");
      if (rec.result.is_object()) {
        rec.values = flattenResult(rec.result);
      } else {
        // A done marker without a readable result: report the run as failed, with the reason.
        rec.status = RunStatus::Failed;
        rec.marker = {{"error", "done.json present but result.json missing or unreadable"}};
      }
    } else if (rec.status == RunStatus::Failed) {
      rec.marker = readJson(dir / kFailedMarker);
    }
    rec.run = std::move(r);
    out.push_back(std::move(rec));
  }
  return out;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Configurations and grouping

struct ConfKey {
  int shape = 0;
  double xs = 0.0;
  double mu = 0.0;
  bool periodic = false;
  double width = 0.0;
  auto operator<=>(const ConfKey&) const = default;
};

ConfKey confKey(const core::RunConfig& c) {
  return {static_cast<int>(c.population.shape), c.population.smallFraction, c.box.wallFriction, c.box.periodicY,
          c.box.width};
}

// Series of a geometrical-model fit: everything but the width.
struct SeriesKey {
  int shape = 0;
  double xs = 0.0;
  double mu = 0.0;
  auto operator<=>(const SeriesKey&) const = default;
};

SeriesKey seriesOf(const ConfKey& k) { return {k.shape, k.xs, k.mu}; }

std::string num(double v) { return fmt::format("{:g}", v); }

std::string familyOf(int shape, double xs) {
  return fmt::format("{}{}", xs > 0.0 ? "B" : "M", shape == static_cast<int>(core::ShapeKind::Sphere) ? "SP" : "PP");
}

std::string widthText(const ConfKey& k) { return k.periodic ? fmt::format("biperiodic ({})", num(k.width)) : num(k.width); }

std::string seriesText(const SeriesKey& s) {
  return fmt::format("{} x_S={} mu_w={}", familyOf(s.shape, s.xs), num(s.xs), num(s.mu));
}

// Mean +- std (n): 4 significant digits for the mean, 2 for the spread.
std::string statText(const ReplicaStat& s) {
  if (s.n == 0) return "missing";
  if (s.n == 1) return fmt::format("{:.4g} (n=1)", s.mean);
  return fmt::format("{:.4g} ± {:.2g} (n={})", s.mean, s.std, s.n);
}

std::string diffText(const BackendDifference& d) {
  if (d.uncertainty) {
    // A difference more than twice its uncertainty is flagged: the backends disagree.
    const bool significant = std::abs(d.value) > 2.0 * *d.uncertainty && *d.uncertainty > 0.0;
    return fmt::format("{:+.3g} ± {:.2g}{}", d.value, *d.uncertainty, significant ? " (*)" : "");
  }
  return fmt::format("{:+.3g} (no uncertainty: n<2)", d.value);
}

std::string htmlEscape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string mdEscape(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += "\\|";
    else out += c;
  }
  return out;
}

// Both documents are written side by side by the same calls, so they cannot drift apart.
class Doc {
 public:
  void heading(int level, const std::string& text) {
    md_ << std::string(static_cast<std::size_t>(level), '#') << ' ' << text << "\n\n";
    html_ << fmt::format("<h{0}>{1}</h{0}>\n", level, htmlEscape(text));
  }
  void para(const std::string& text) {
    md_ << text << "\n\n";
    html_ << "<p>" << htmlEscape(text) << "</p>\n";
  }
  void bullets(const std::vector<std::string>& items) {
    html_ << "<ul>\n";
    for (const auto& i : items) {
      md_ << "- " << i << "\n";
      html_ << "<li>" << htmlEscape(i) << "</li>\n";
    }
    md_ << "\n";
    html_ << "</ul>\n";
  }
  void table(const std::vector<std::string>& head, const std::vector<std::vector<std::string>>& rows) {
    if (rows.empty()) {
      para("(no data)");
      return;
    }
    md_ << '|';
    html_ << "<table>\n<tr>";
    for (const auto& h : head) {
      md_ << ' ' << mdEscape(h) << " |";
      html_ << "<th>" << htmlEscape(h) << "</th>";
    }
    md_ << "\n|";
    for (std::size_t i = 0; i < head.size(); ++i) md_ << "---|";
    md_ << '\n';
    html_ << "</tr>\n";
    for (const auto& row : rows) {
      md_ << '|';
      html_ << "<tr>";
      for (const auto& c : row) {
        md_ << ' ' << mdEscape(c) << " |";
        const bool flag = c == "missing" || c.find("FAILED") != std::string::npos ||
                          c.find("(*)") != std::string::npos || c.find("NOT") != std::string::npos ||
                          c == "failed" || c == "pending" || c == "incomplete";
        html_ << (flag ? "<td class=\"flag\">" : "<td>") << htmlEscape(c) << "</td>";
      }
      md_ << "\n";
      html_ << "</tr>\n";
    }
    md_ << "\n";
    html_ << "</table>\n";
  }
  void figure(const std::string& stem, const std::string& caption, const std::string& svg) {
    if (svg.empty()) {
      md_ << fmt::format("*Figure {}: {}* (not drawn; data in [figures/{}.csv](figures/{}.csv), script "
                         "figures/{}.gp)\n\n",
                         stem, caption, stem, stem, stem);
      html_ << fmt::format("<p class=\"fig\"><em>Figure {}: {}</em> (not drawn; data in figures/{}.csv)</p>\n", stem,
                           htmlEscape(caption), stem);
      return;
    }
    md_ << fmt::format("![{}](figures/{}.svg)\n\n*{}* (data: [figures/{}.csv](figures/{}.csv))\n\n", caption, stem,
                       caption, stem, stem);
    html_ << "<figure>" << svg << "<figcaption>" << htmlEscape(caption) << " (data: figures/" << stem
          << ".csv)</figcaption></figure>\n";
  }
  std::string markdown() const { return md_.str(); }
  std::string html(const std::string& title) const {
    return fmt::format(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\n"
        "body{{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}}\n"
        "table{{border-collapse:collapse;margin:0.5em 0 1.5em;font-size:90%}}\n"
        "th,td{{border:1px solid #bbb;padding:2px 6px;text-align:right}} th{{background:#eee}}\n"
        "td.flag{{background:#fde2e2}} figure{{margin:1em 0}} figure svg{{max-width:100%;height:auto}}\n"
        "figcaption{{font-size:90%;color:#444}}\n</style></head><body>\n{}</body></html>\n",
        htmlEscape(title), html_.str());
  }

 private:
  std::ostringstream md_;
  std::ostringstream html_;
};

// ---------------------------------------------------------------------------------------------
// Figures: CSV (long format: series,x,y,err) + gnuplot script + SVG

struct Series {
  std::string name;
  int color = 1;
  bool dashed = false;  // second backend
  bool lines = true;
  std::vector<std::array<double, 3>> points;  // x, y, err
  bool markers = true;  // false: a plain line (dense profiles)
};

struct Plot {
  std::string stem, caption, xlabel, ylabel;
  std::vector<Series> series;
  std::vector<std::string> functions;  // "f(x) = ...; title" pairs written as plot terms
  bool xFromZero = false;
};

class FigureWriter {
 public:
  FigureWriter(fs::path dir, fs::path gnuplot) : dir_(std::move(dir)), gnuplot_(std::move(gnuplot)) {
    fs::create_directories(dir_);
    if (!gnuplot_.empty()) {
      const std::string probe = fmt::format("'{}' --version >/dev/null 2>&1", gnuplot_.string());
      available_ = std::system(probe.c_str()) == 0;
    }
  }
  bool available() const { return available_; }
  std::size_t count() const { return count_; }

  // Returns the SVG text (empty when not drawn).
  std::string draw(const Plot& p) {
    ++count_;
    std::ostringstream csv;
    csv.precision(10);
    csv << "series,x,y,err\n";
    for (const Series& s : p.series)
      for (const auto& pt : s.points) csv << s.name << ',' << pt[0] << ',' << pt[1] << ',' << pt[2] << '\n';
    core::writeFileAtomically(dir_ / (p.stem + ".csv"), csv.str());

    std::ostringstream gp;
    gp << "# confpack report figure: " << p.caption << "\n"
       << "set terminal svg size 760,480 dynamic noenhanced font 'Helvetica,12' background rgb 'white'\n"
       << "set output '" << p.stem << ".svg'\n"
       << "set datafile separator ','\n"
       << "set key outside right top box font ',10'\n"
       << "set grid\n"
       << "set xlabel '" << p.xlabel << "'\nset ylabel '" << p.ylabel << "'\n";
    if (p.xFromZero) gp << "set xrange [0:*]\n";
    gp << "set title '" << p.caption << "' noenhanced font ',11'\n";
    std::vector<std::string> terms;
    for (const Series& s : p.series) {
      // Rows of other series give an undefined x and are skipped; rows of one series are
      // contiguous in the CSV, so its line is not broken.
      const std::string sel = fmt::format("(strcol(1) eq \"{}\" ? $2 : 1/0)", s.name);
      const std::string style = fmt::format("lc {} dt {} pt {}", s.color, s.dashed ? 2 : 1, s.dashed ? 6 : 7);
      bool hasErr = false;
      for (const auto& pt : s.points) hasErr = hasErr || pt[2] > 0.0;
      if (hasErr)
        terms.push_back(fmt::format("'{}.csv' skip 1 using {}:3:4 with yerrorbars {} notitle", p.stem, sel, style));
      terms.push_back(fmt::format("'{}.csv' skip 1 using {}:3 with {} {} title \"{}\" noenhanced", p.stem, sel,
                                  !s.markers ? "lines" : s.lines ? "linespoints" : "points", style, s.name));
    }
    for (const std::string& f : p.functions) terms.push_back(f);
    gp << "plot " << (terms.empty() ? std::string("NaN notitle") : "\\\n  ");
    for (std::size_t i = 0; i < terms.size(); ++i) gp << terms[i] << (i + 1 < terms.size() ? ", \\\n  " : "\n");
    core::writeFileAtomically(dir_ / (p.stem + ".gp"), gp.str());

    if (!available_) return {};
    const std::string cmd = fmt::format("cd '{}' && '{}' '{}.gp' >'{}.log' 2>&1", dir_.string(), gnuplot_.string(),
                                        p.stem, p.stem);
    if (std::system(cmd.c_str()) != 0) return {};
    fs::remove(dir_ / (p.stem + ".log"));
    std::ifstream in(dir_ / (p.stem + ".svg"));
    std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // Inline SVG in HTML must not carry the XML declaration.
    if (const auto pos = svg.find("<svg"); pos != std::string::npos) svg = svg.substr(pos);
    return svg;
  }

 private:
  fs::path dir_;
  fs::path gnuplot_;
  bool available_ = false;
  std::size_t count_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Profiles written by the runs (CSV with '#' metadata lines and one header line)

struct CsvTable {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
};

std::optional<CsvTable> readCsv(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  CsvTable t;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (t.columns.empty()) {
      t.columns = cells;
      continue;
    }
    std::vector<double> row;
    for (const auto& c : cells) {
      try {
        row.push_back(std::stod(c));
      } catch (...) {
        row.push_back(std::nan(""));
      }
    }
    if (row.size() == t.columns.size()) t.rows.push_back(std::move(row));
  }
  if (t.columns.size() < 2 || t.rows.empty()) return std::nullopt;
  return t;
}

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

// ---------------------------------------------------------------------------------------------
// Sections: which result keys go where (in the order of docs/model.md's measurements)

struct Section {
  std::string title;
  std::vector<std::string> prefixes;  // key starts with one of these
};

const std::vector<Section>& sections() {
  static const std::vector<Section> s = {
      {"Solid fraction", {"solid_fraction", "bulk_region", "free_surface"}},
      {"Profile fit phi(y)", {"profile_fit"}},
      {"Coordination", {"coordination", "hyperstaticity", "wall_contacts"}},
      {"Interpenetration, % by volume", {"interpenetration"}},
      {"Homogeneity", {"homogeneity"}},
      {"Order: anisotropy and nematic order", {"anisotropy", "fabric", "nematic", "orientation"}},
      {"Equilibrium", {"equilibrium"}},
      {"Cost (wall time, steps, solver iterations)", {"timing", "deposit"}},
  };
  return s;
}

int sectionOf(const std::string& key) {
  for (std::size_t i = 0; i < sections().size(); ++i)
    for (const auto& p : sections()[i].prefixes)
      if (key.rfind(p, 0) == 0) return static_cast<int>(i);
  return -1;  // "other quantities"
}

}  // namespace

ReportSummary writeReport(const fs::path& sweepDir, const fs::path& outDir, const ReportOptions& options) {
  SweepSpec spec;
  const std::vector<RunRecord> records = loadStudy(sweepDir, &spec);
  fs::create_directories(outDir);
  FigureWriter figures(outDir / "figures", options.gnuplot);
  ReportSummary summary;
  summary.runs = records.size();

  // Backends in table order, and the runs of each (configuration, backend).
  std::vector<std::string> backends;
  std::map<ConfKey, std::map<std::string, std::vector<const RunRecord*>>> groups;
  std::set<std::string> keys;
  std::set<std::string> csvNames;
  for (const RunRecord& r : records) {
    if (std::find(backends.begin(), backends.end(), r.run.config.backend) == backends.end())
      backends.push_back(r.run.config.backend);
    groups[confKey(r.run.config)][r.run.config.backend].push_back(&r);
    if (r.status == RunStatus::Done) {
      ++summary.done;
      for (const auto& [k, v] : r.values) keys.insert(k);
      for (const auto& e : fs::directory_iterator(sweepDir / "runs" / r.run.name))
        if (e.path().extension() == ".csv") csvNames.insert(e.path().filename().string());
      const auto it = r.values.find("equilibrium/reached");
      if (it != r.values.end() && it->second && *it->second == 0.0) ++summary.unequilibrated;
    } else if (r.status == RunStatus::Failed) {
      ++summary.failed;
    } else {
      ++summary.missing;
    }
  }

  auto stat = [&](const std::vector<const RunRecord*>& runs, const std::string& key) {
    std::vector<double> v;
    for (const RunRecord* r : runs) {
      if (r->status != RunStatus::Done) continue;
      const auto it = r->values.find(key);
      if (it != r->values.end() && it->second) v.push_back(*it->second);
    }
    return replicaStat(v);
  };
  auto applies = [&](const std::string& key) {
    // A key that is null in every run (nematic order of spheres) does not apply to this study.
    for (const RunRecord& r : records) {
      const auto it = r.values.find(key);
      if (it != r.values.end() && it->second) return true;
    }
    return false;
  };
  auto statOf = [&](const ConfKey& k, const std::string& backend, const std::string& key) {
    const auto g = groups.find(k);
    if (g == groups.end() || !g->second.count(backend)) return ReplicaStat{};
    return stat(g->second.at(backend), key);
  };

  Doc doc;
  const std::string title = fmt::format("confpack study report: {}", spec.name);
  doc.heading(1, title);
  {
    const std::time_t t = std::time(nullptr);
    char when[32];
    std::tm tm{};
    gmtime_r(&t, &tm);
    std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", &tm);
    doc.para(fmt::format("Sweep folder: {}. Written {} by confpack {}. {} runs: {} done, {} failed, {} missing "
                         "(not run or interrupted), {} done but not equilibrated.",
                         fs::absolute(sweepDir).string(), when, CONFPACK_VERSION, summary.runs, summary.done,
                         summary.failed, summary.missing, summary.unequilibrated));
  }
  doc.para(
      "How to read the tables: each cell is the mean ± sample standard deviation over the replicas (seeds) that "
      "finished, with their number n. The difference column is the first backend minus the second with the "
      "standard error of a difference of independent means, sqrt(s1²/n1 + s2²/n2); (*) marks a difference "
      "larger than twice its uncertainty. Both backends of one (configuration, seed) compact the same deposit. "
      "Units: lengths in large-grain diameters d_L, times in sqrt(d_L/g), wall time in seconds.");
  if (!figures.available())
    doc.para(options.gnuplot.empty()
                 ? "Figures were not drawn (disabled); their CSV data and gnuplot scripts are in figures/."
                 : fmt::format("gnuplot ('{}') was not found: figures are not drawn. Their CSV data and gnuplot "
                               "scripts are in figures/ (install gnuplot-nox and rerun `confpack report`).",
                               options.gnuplot.string()));

  // ---- Runs and their status
  doc.heading(2, "Runs");
  {
    std::vector<std::vector<std::string>> problems;
    std::vector<std::vector<std::string>> all;
    for (const RunRecord& r : records) {
      const auto value = [&](const std::string& k, const char* f) -> std::string {
        const auto it = r.values.find(k);
        if (it == r.values.end() || !it->second) return "";
        return fmt::format(fmt::runtime(f), *it->second);
      };
      std::string status(toString(r.status));
      std::string note;
      if (r.status == RunStatus::Failed) note = r.marker.is_object() ? r.marker.value("error", "") : "";
      if (r.status == RunStatus::Done) {
        const auto it = r.values.find("equilibrium/reached");
        if (it != r.values.end() && it->second && *it->second == 0.0) {
          status = "done, NOT equilibrated";
          // A quasi-static run that is not at rest has used all its finisher steps.
          const auto finisher = r.values.find("timing/stages/quasi_static/steps");
          note = finisher != r.values.end() && finisher->second
                     ? fmt::format("finisher not at rest after {:.0f} steps", *finisher->second)
                     : "stopped at the time limit";
        }
      }
      if (r.status == RunStatus::Pending || r.status == RunStatus::Incomplete) note = "missing: not run or interrupted";
      std::vector<std::string> row = {r.run.name, r.run.label(), status, value("solid_fraction", "{:.4f}"),
                                      value("timing/wall_s", "{:.1f}"), note};
      if (r.status != RunStatus::Done || !note.empty()) problems.push_back(row);
      all.push_back(std::move(row));
    }
    const std::vector<std::string> head = {"run", "configuration", "status", "phi", "wall [s]", "note"};
    if (problems.empty()) {
      doc.para("Every run finished and reached equilibrium.");
    } else {
      doc.para("Runs that are missing, failed or did not reach equilibrium (their values are absent from the "
               "tables below, or, for unequilibrated runs, included but flagged here):");
      doc.table(head, problems);
    }
    doc.heading(3, "All runs");
    doc.table(head, all);
  }

  // ---- Quantity tables, section by section
  std::vector<std::string> confHead = {"family", "x_S [%]", "W [d_L]", "mu_w"};
  for (const auto& b : backends) confHead.push_back(b);
  const bool pair = backends.size() >= 2;
  if (pair) confHead.push_back(fmt::format("{} − {}", backends[0], backends[1]));
  auto quantityTable = [&](const std::string& key) {
    std::vector<std::vector<std::string>> rows;
    for (const auto& [k, byBackend] : groups) {
      std::vector<std::string> row = {familyOf(k.shape, k.xs), num(k.xs), widthText(k), k.periodic ? "-" : num(k.mu)};
      std::vector<ReplicaStat> stats;
      for (const auto& b : backends) {
        stats.push_back(statOf(k, b, key));
        row.push_back(byBackend.count(b) ? statText(stats.back()) : "not in study");
      }
      if (pair) row.push_back(stats[0].n && stats[1].n ? diffText(backendDifference(stats[0], stats[1])) : "");
      rows.push_back(std::move(row));
    }
    doc.table(confHead, rows);
  };

  std::vector<std::vector<std::string>> sectionKeys(sections().size() + 1);
  for (const std::string& k : keys) {
    const int s = sectionOf(k);
    sectionKeys[s < 0 ? sections().size() : static_cast<std::size_t>(s)].push_back(k);
  }

  // Fits of the geometrical model, per series and backend.
  struct FitRow {
    SeriesKey series;
    std::string backend;
    std::optional<analysis::ConfinementFit> fit;
    std::string why;  // when no fit
    std::vector<std::array<double, 3>> points;  // 1/W, mean, sigma
    std::optional<ReplicaStat> biperiodic;
  };
  auto fitsFor = [&](const std::string& key) {
    std::vector<FitRow> out;
    std::set<SeriesKey> seriesSet;
    for (const auto& [k, _] : groups) seriesSet.insert(seriesOf(k));
    for (const SeriesKey& s : seriesSet)
      for (const auto& b : backends) {
        FitRow row{s, b, std::nullopt, "", {}, std::nullopt};
        std::vector<double> w, v, sigma;
        bool weighted = true;
        for (const auto& [k, _] : groups) {
          if (seriesOf(k) != s) continue;
          const ReplicaStat st = statOf(k, b, key);
          if (st.n == 0) continue;
          if (k.periodic) {
            row.biperiodic = st;
            continue;
          }
          w.push_back(k.width);
          v.push_back(st.mean);
          // The replicas' standard error of the mean weighs each width; with a single replica
          // (or identical values) there is none and the fit is unweighted.
          const double se = st.n >= 2 ? st.std / std::sqrt(static_cast<double>(st.n)) : 0.0;
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
  };

  auto fitSection = [&](const std::string& key, const std::string& quantity, const std::string& cName,
                        const std::string& stem) {
    const std::vector<FitRow> fits = fitsFor(key);
    if (fits.empty()) return fits;
    doc.heading(3, fmt::format("Geometrical model: {}(W) = {}_bulk − {}/W", quantity, quantity, cName));
    std::vector<std::vector<std::string>> rows;
    for (const FitRow& f : fits) {
      std::vector<std::string> row = {seriesText(f.series), f.backend, std::to_string(f.points.size())};
      if (f.fit) {
        row.push_back(fmt::format("{:.4f} ± {:.2g}", f.fit->bulk, f.fit->bulkError));
        row.push_back(fmt::format("{:.3f} ± {:.2g}", f.fit->c, f.fit->cError));
        row.push_back(fmt::format("{:.3f}", f.fit->zeta()));
        row.push_back(f.fit->weighted ? "weighted" : "unweighted");
        row.push_back(f.fit->dof > 0 ? fmt::format("{:.3g}/{}", f.fit->chiSquare, f.fit->dof) : "exact (2 points)");
        row.push_back(f.fit->quality ? fmt::format("{:.3g}", *f.fit->quality) : "-");
      } else {
        for (int i = 0; i < 5; ++i) row.push_back(i == 0 ? "no fit: " + f.why : "");
      }
      row.push_back(f.biperiodic ? statText(*f.biperiodic) : "-");
      rows.push_back(std::move(row));
    }
    doc.table({"series", "backend", "widths", quantity + "_bulk", cName + " [d_L]",
               "zeta = " + cName + "/" + quantity + "_bulk", "weights", "chi²/dof", "Q", "biperiodic"},
              rows);
    // Backend differences of the fitted parameters.
    if (pair) {
      std::vector<std::vector<std::string>> diffs;
      for (const FitRow& a : fits) {
        if (a.backend != backends[0] || !a.fit) continue;
        for (const FitRow& b : fits)
          if (b.backend == backends[1] && b.series == a.series && b.fit)
            diffs.push_back({seriesText(a.series),
                             fmt::format("{:+.4f} ± {:.2g}", a.fit->bulk - b.fit->bulk,
                                         std::hypot(a.fit->bulkError, b.fit->bulkError)),
                             fmt::format("{:+.3f} ± {:.2g}", a.fit->c - b.fit->c, std::hypot(a.fit->cError, b.fit->cError))});
      }
      if (!diffs.empty()) {
        doc.para(fmt::format("Backend differences of the fitted parameters ({} − {}, uncertainty from the two fits' "
                             "standard errors):",
                             backends[0], backends[1]));
        doc.table({"series", quantity + "_bulk", cName}, diffs);
      }
    }
    // Figure: values against d_L/W with the fitted lines; biperiodic at d_L/W = 0.
    Plot p{stem, fmt::format("{} against d_L/W with the fits {}_bulk - {}/W (biperiodic at 0)", quantity, quantity, cName),
           "d_L / W", quantity, {}, {}, true};
    int color = 0;
    std::map<SeriesKey, int> colors;
    for (const FitRow& f : fits) {
      if (!colors.count(f.series)) colors[f.series] = ++color;
      const bool dashed = f.backend != backends[0];
      Series s{fmt::format("{} {}", seriesText(f.series), f.backend), colors[f.series], dashed, false, f.points};
      if (f.biperiodic) s.points.insert(s.points.begin(), {0.0, f.biperiodic->mean, f.biperiodic->n >= 2 ? f.biperiodic->std / std::sqrt(double(f.biperiodic->n)) : 0.0});
      p.series.push_back(std::move(s));
      if (f.fit)
        p.functions.push_back(fmt::format("[0:*] {:.10g} - {:.10g}*x lc {} dt {} notitle", f.fit->bulk, f.fit->c,
                                          colors[f.series], dashed ? 2 : 1));
    }
    doc.figure(stem, p.caption, figures.draw(p));
    return fits;
  };

  std::vector<FitRow> phiFits;
  for (std::size_t s = 0; s <= sections().size(); ++s) {
    const bool other = s == sections().size();
    std::vector<std::string> shown;
    for (const auto& k : sectionKeys[s])
      if (applies(k)) shown.push_back(k);
    if (other && shown.empty()) continue;
    doc.heading(2, other ? "Other quantities in result.json" : sections()[s].title);
    std::vector<std::string> notApplicable;
    for (const auto& k : sectionKeys[s])
      if (!applies(k)) notApplicable.push_back(k);
    if (shown.empty() && notApplicable.empty()) doc.para("No run of this study reported these quantities.");
    for (const auto& k : shown) {
      doc.heading(3, k);
      quantityTable(k);
    }
    if (!notApplicable.empty()) {
      std::string list;
      for (const auto& k : notApplicable) list += (list.empty() ? "" : ", ") + k;
      doc.para("Not applicable to any run of this study (null in every result.json): " + list + ".");
    }
    if (s == 0 && keys.count("solid_fraction")) phiFits = fitSection("solid_fraction", "phi", "C", "phi_vs_invW");
    if (s == 2 && keys.count("coordination/Z")) fitSection("coordination/Z", "Z", "C_Z", "Z_vs_invW");
    if (s == 1 && keys.count("profile_fit/lambda_L")) {
      // lambda_L from the widest confined sample of each series (the wall effect of one wall, least
      // disturbed by the other), against x_S and against C of the phi(W) fit.
      Plot byXs{"lambdaL_vs_xS", "lambda_L (widest confined sample) against x_S", "x_S [%]", "lambda_L [d_L]", {}, {}, false};
      Plot byC{"lambdaL_vs_C", "lambda_L against C of the phi(W) fit, with a line through the origin", "C [d_L]",
               "lambda_L [d_L]", {}, {}, true};
      std::vector<std::vector<std::string>> originRows;
      for (std::size_t bi = 0; bi < backends.size(); ++bi) {
        const std::string& b = backends[bi];
        std::map<std::pair<int, double>, Series> bySeries;
        std::vector<double> cs, ls, sig;
        Series cSeries{b, static_cast<int>(bi) + 1, bi > 0, false, {}};
        std::set<SeriesKey> seen;
        for (const auto& [k, _] : groups) seen.insert(seriesOf(k));
        for (const SeriesKey& sk : seen) {
          const ConfKey* widest = nullptr;
          for (const auto& [k, __] : groups)
            if (seriesOf(k) == sk && !k.periodic && statOf(k, b, "profile_fit/lambda_L").n > 0 &&
                (!widest || k.width > widest->width))
              widest = &k;
          if (!widest) continue;
          const ReplicaStat st = statOf(*widest, b, "profile_fit/lambda_L");
          const double err = st.n >= 2 ? st.std / std::sqrt(double(st.n)) : 0.0;
          auto& ser = bySeries[{sk.shape, sk.mu}];
          if (ser.name.empty())
            ser = Series{fmt::format("{} mu_w={} {}", sk.shape == 0 ? "spheres" : "pinacoids", num(sk.mu), b),
                         static_cast<int>(bySeries.size()), bi > 0, true, {}};
          ser.points.push_back({sk.xs, st.mean, err});
          for (const FitRow& f : phiFits)
            if (f.series == sk && f.backend == b && f.fit) {
              cs.push_back(f.fit->c);
              ls.push_back(st.mean);
              sig.push_back(err);
              cSeries.points.push_back({f.fit->c, st.mean, err});
            }
        }
        for (auto& [_, ser] : bySeries) byXs.series.push_back(ser);
        if (!cSeries.points.empty()) byC.series.push_back(cSeries);
        if (!cs.empty()) {
          bool weighted = true;
          for (double e : sig) weighted = weighted && e > 0.0;
          try {
            const analysis::ProportionalFit f = analysis::fitThroughOrigin(cs, ls, weighted ? sig : std::vector<double>{});
            originRows.push_back({b, std::to_string(cs.size()), fmt::format("{:.4f} ± {:.2g}", f.slope, f.slopeError),
                                  weighted ? "weighted" : "unweighted"});
            byC.functions.push_back(fmt::format("[0:*] {:.10g}*x lc {} dt {} notitle", f.slope, bi + 1, bi > 0 ? 2 : 1));
          } catch (const std::exception& e) {
            originRows.push_back({b, std::to_string(cs.size()), std::string("no fit: ") + e.what(), ""});
          }
        }
      }
      doc.heading(3, "lambda_L against x_S and against C");
      if (!byXs.series.empty()) doc.figure(byXs.stem, byXs.caption, figures.draw(byXs));
      if (!originRows.empty()) {
        doc.para("Linear fit through the origin lambda_L = k C per backend:");
        doc.table({"backend", "points", "k = lambda_L / C", "weights"}, originRows);
        doc.figure(byC.stem, byC.caption, figures.draw(byC));
      }
    }
  }

  // ---- Profiles written by the runs (CSV), averaged over replicas
  if (!csvNames.empty()) {
    doc.heading(2, "Profiles");
    doc.para("Profiles as written by the runs (one CSV per quantity in each run folder), averaged over the "
             "replicas; solid lines are the first backend, dashed the second.");
    std::set<SeriesKey> seriesSet;
    for (const auto& [k, _] : groups) seriesSet.insert(seriesOf(k));
    int figureIndex = 0;
    for (const std::string& name : csvNames) {
      const std::string base = fs::path(name).stem().string();
      for (const SeriesKey& sk : seriesSet) {
        std::map<std::string, std::vector<Series>> byColumn;
        std::vector<std::string> columnOrder;
        std::string xLabel;
        int color = 0;
        for (const auto& [k, byBackend] : groups) {
          if (seriesOf(k) != sk) continue;
          ++color;
          for (std::size_t bi = 0; bi < backends.size(); ++bi) {
            if (!byBackend.count(backends[bi])) continue;
            std::vector<CsvTable> tables;
            for (const RunRecord* r : byBackend.at(backends[bi]))
              if (r->status == RunStatus::Done)
                if (auto t = readCsv(sweepDir / "runs" / r->run.name / name)) tables.push_back(std::move(*t));
            if (tables.empty()) continue;
            const CsvTable avg = averageProfiles(tables);
            xLabel = avg.columns[0];
            // At most four value columns per profile keep the figures readable.
            for (std::size_t c = 1; c < avg.columns.size() && c <= 4; ++c) {
              if (!byColumn.count(avg.columns[c])) columnOrder.push_back(avg.columns[c]);
              Series s{fmt::format("W={} {} (n={})", widthText(k), backends[bi], tables.size()), color, bi > 0, true, {}};
              s.markers = false;
              for (const auto& row : avg.rows)
                if (std::isfinite(row[c])) s.points.push_back({row[0], row[c], 0.0});
              byColumn[avg.columns[c]].push_back(std::move(s));
            }
          }
        }
        for (const std::string& col : columnOrder) {
          Plot p{fmt::format("profile_{:03d}_{}", ++figureIndex, base),
                 fmt::format("{}: {} for {}", base, col, seriesText(sk)), xLabel, col, byColumn[col], {}, false};
          doc.figure(p.stem, p.caption, figures.draw(p));
        }
      }
    }
  }

  // ---- Cost of every run
  doc.heading(2, "Cost of each run");
  {
    std::vector<std::string> costKeys;
    for (const std::string& k : keys)
      if (k.rfind("timing/", 0) == 0 && k.find("phases") == std::string::npos) costKeys.push_back(k);
    std::vector<std::string> head = {"run", "configuration", "status"};
    for (const auto& k : costKeys) head.push_back(k.substr(7));
    std::vector<std::vector<std::string>> rows;
    std::map<std::string, double> totalWall;
    for (const RunRecord& r : records) {
      std::vector<std::string> row = {r.run.name, r.run.label(), std::string(toString(r.status))};
      for (const auto& k : costKeys) {
        const auto it = r.values.find(k);
        row.push_back(it != r.values.end() && it->second ? fmt::format("{:.4g}", *it->second) : "");
      }
      const auto w = r.values.find("timing/wall_s");
      if (w != r.values.end() && w->second) totalWall[r.run.config.backend] += *w->second;
      rows.push_back(std::move(row));
    }
    std::string totals;
    for (const auto& [b, t] : totalWall) totals += fmt::format("{}{}: {:.0f} s", totals.empty() ? "" : ", ", b, t);
    if (!totals.empty()) doc.para("Total compaction wall time per backend: " + totals + ".");
    doc.table(head, rows);
  }

  doc.heading(2, "Method");
  doc.bullets({
      "Study definition: " + sweepDir.string() + "/sweep.json (the sweep file and the expanded run table); each "
      "run's fully resolved configuration is in runs/<name>/config.json and its result.json.",
      "Mean and standard deviation are over the replicas (seeds) that finished; missing runs are listed above and "
      "excluded from the means.",
      "Geometrical model (docs/model.md): linear least squares in 1/W over the confined widths (GSL); weighted by the "
      "replicas' standard error of the mean when every width has at least two differing replicas, unweighted "
      "otherwise (its errors are then estimated from the scatter). The biperiodic value is shown next to the "
      "fitted bulk value as a check.",
      "Backend differences: first minus second backend, uncertainty sqrt(s1²/n1 + s2²/n2).",
  });

  summary.figures = figures.count();
  summary.gnuplotUsed = figures.available();
  summary.markdown = outDir / "report.md";
  summary.html = outDir / "report.html";
  core::writeFileAtomically(summary.markdown, doc.markdown());
  core::writeFileAtomically(summary.html, doc.html(title));
  return summary;
}

}  // namespace confpack::study
