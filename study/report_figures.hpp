#pragma once
// The report's figures: for each, figures/STEM.csv (long format: series,x,y,err), a gnuplot script
// figures/STEM.gp and, when gnuplot runs, figures/STEM.svg. gnuplot is started without a shell
// (study/process.hpp), in figures/, with the script's file name as its argument; a run that fails,
// times out or leaves no complete SVG is an error of that figure (its output stays in
// figures/STEM.log), never a silently missing or broken drawing.
#include <array>
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "study/report_document.hpp"

namespace confpack::study {

struct Series {
  std::string name;
  int color = 1;
  bool dashed = false;  ///< second backend
  bool lines = true;
  std::vector<std::array<double, 3>> points;  ///< x, y, err
  bool markers = true;                        ///< false: a plain line (dense profiles)
  int pointType = 0;                          ///< gnuplot's pt; 0: by backend (7 solid, 6 dashed)
};

struct Plot {
  std::string stem, caption, xlabel, ylabel;
  std::vector<Series> series;
  std::vector<std::string> functions;  ///< gnuplot plot terms drawn after the series (fitted lines)
  bool xFromZero = false;
};

/// The gnuplot script of a plot, reading STEM.csv and writing STEM.svg in its own folder.
std::string gnuplotScript(const Plot& p);

class FigureWriter {
 public:
  /// gnuplot: the executable (searched in PATH without a '/'); empty = write data and scripts only.
  /// It is probed once with --version; when that fails no figure is drawn.
  FigureWriter(std::filesystem::path dir, std::filesystem::path gnuplot,
               std::chrono::milliseconds timeout = std::chrono::seconds(120));
  bool available() const { return available_; }
  /// Why a gnuplot that was asked for cannot be used: "was not found (...)" when it could not
  /// start, "failed its check (`gnuplot --version` exited with status 3)" when it ran and failed;
  /// empty when it is available or none was asked for.
  const std::string& problem() const { return problem_; }
  std::size_t count() const { return count_; }
  /// "figure STEM: ..." for every figure gnuplot failed on.
  const std::vector<std::string>& errors() const { return errors_; }

  /// Writes the CSV and the script, runs gnuplot when available and returns the figure block:
  /// its SVG (without the XML declaration, to be inlined in HTML), or its error.
  Figure draw(const Plot& p);

 private:
  // "" with the SVG in text, or why it failed.
  std::string runGnuplot(const std::string& stem, std::string& text);

  std::filesystem::path dir_;
  std::filesystem::path gnuplot_;
  std::chrono::milliseconds timeout_;
  bool available_ = false;
  std::string problem_;
  std::size_t count_ = 0;
  std::vector<std::string> errors_;
};

}  // namespace confpack::study
