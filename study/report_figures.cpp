#include "study/report_figures.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>

#include "core/packing_io.hpp"
#include "study/process.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

std::string gnuplotScript(const Plot& p) {
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
    const std::string style = fmt::format("lc {} dt {} pt {}", s.color, s.dashed ? 2 : 1,
                                          s.pointType ? s.pointType
                                          : s.dashed  ? 6
                                                      : 7);
    bool hasErr = false;
    for (const auto& pt : s.points) hasErr = hasErr || pt[2] > 0.0;
    if (hasErr)
      terms.push_back(fmt::format("'{}.csv' skip 1 using {}:3:4 with yerrorbars {} notitle", p.stem, sel, style));
    terms.push_back(fmt::format("'{}.csv' skip 1 using {}:3 with {} {} title \"{}\" noenhanced", p.stem, sel,
                                !s.markers ? "lines"
                                : s.lines  ? "linespoints"
                                           : "points",
                                style, s.name));
  }
  for (const std::string& f : p.functions) terms.push_back(f);
  gp << "plot " << (terms.empty() ? std::string("NaN notitle") : "\\\n  ");
  for (std::size_t i = 0; i < terms.size(); ++i) gp << terms[i] << (i + 1 < terms.size() ? ", \\\n  " : "\n");
  return gp.str();
}

FigureWriter::FigureWriter(fs::path dir, fs::path gnuplot, std::chrono::milliseconds timeout)
    : dir_(std::move(dir)), gnuplot_(std::move(gnuplot)), timeout_(timeout) {
  fs::create_directories(dir_);
  if (gnuplot_.empty()) return;
  const ProcessResult probe = runProcess({gnuplot_.string(), "--version"}, {{}, {}, timeout_});
  available_ = probe.ok();
  // A program that ran and failed is not one that is missing: say which, with its exit status.
  if (!available_)
    problem_ = probe.started
                   ? fmt::format("failed its check (`{} --version` {})", gnuplot_.string(), probe.describe(timeout_))
                   : fmt::format("was not found ({})", probe.error);
}

Figure FigureWriter::draw(const Plot& p) {
  ++count_;
  std::ostringstream csv;
  csv.precision(10);
  csv << "series,x,y,err\n";
  for (const Series& s : p.series)
    for (const auto& pt : s.points) csv << s.name << ',' << pt[0] << ',' << pt[1] << ',' << pt[2] << '\n';
  core::writeFileAtomically(dir_ / (p.stem + ".csv"), csv.str());
  core::writeFileAtomically(dir_ / (p.stem + ".gp"), gnuplotScript(p));

  Figure f{p.stem, p.caption, {}, {}};
  if (!available_) return f;
  std::string svg;
  if (std::string why = runGnuplot(p.stem, svg); !why.empty()) {
    f.error = fmt::format("gnuplot failed: {} (its output: figures/{}.log)", why, p.stem);
    errors_.push_back(fmt::format("figure {}: {}", p.stem, f.error));
    // A drawing left by a failed run is not kept: it would read as the figure.
    fs::remove(dir_ / (p.stem + ".svg"));
    return f;
  }
  // Inline SVG in HTML must not carry the XML declaration.
  f.svg = svg.substr(svg.find("<svg"));
  return f;
}

std::string FigureWriter::runGnuplot(const std::string& stem, std::string& text) {
  const fs::path log = dir_ / (stem + ".log");
  const fs::path svg = dir_ / (stem + ".svg");
  fs::remove(svg);  // an SVG of an earlier report is not this run's drawing
  const ProcessResult r = runProcess({gnuplot_.string(), stem + ".gp"}, {dir_, log, timeout_});
  if (!r.ok()) {
    const std::string said = lastOutputLine(log);  // gnuplot's error message
    return r.describe(timeout_) + (said.empty() ? "" : ": " + said);
  }
  if (!fs::exists(svg)) return fmt::format("no {}.svg written", stem);
  text = slurp(svg);
  if (text.empty()) return fmt::format("{}.svg is empty", stem);
  if (text.find("<svg") == std::string::npos || text.find("</svg>") == std::string::npos)
    return fmt::format("{}.svg is not a complete SVG", stem);
  fs::remove(log);
  return {};
}

}  // namespace confpack::study
