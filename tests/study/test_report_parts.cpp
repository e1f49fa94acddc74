// The parts of the study report: the document model and its two renderings, the CSV reader, the
// shell-free process runner and the figure writer with a real or a fake gnuplot.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <unistd.h>

#include "study/csv_table.hpp"
#include "study/process.hpp"
#include "study/report_document.hpp"
#include "study/report_figures.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::slurp;

namespace {

// A fresh folder whose name has spaces, single and double quotes and shell metacharacters.
fs::path awkwardDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("confpack test_report_parts " + name + " it's \"quoted\" $HOME; `x` & " +
                        std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// An executable shell script standing in for gnuplot: `--version` succeeds, anything else runs body.
fs::path fakeGnuplot(const fs::path& dir, const std::string& body) {
  const fs::path p = dir / "fake gnuplot's \"bin\"";
  std::ofstream(p) << "#!/bin/sh\nif [ \"$1\" = --version ]; then echo 'gnuplot 0.0 fake'; exit 0; fi\n" << body << "\n";
  fs::permissions(p, fs::perms::owner_all);
  return p;
}

study::Plot tinyPlot(const std::string& stem) {
  study::Plot p{stem, "a tiny plot", "x", "y", {}, {}, false};
  p.series.push_back({"line", 1, false, true, {{{0.0, 1.0, 0.0}}, {{1.0, 2.0, 0.1}}}, true});
  return p;
}

std::string unescapeHtml(std::string s) {
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&amp;", "&"}}) {
    for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size())) s.replace(p, from.size(), to);
  }
  return s;
}

// The cells of the HTML table rows (th and td), unescaped.
std::vector<std::vector<std::string>> htmlCells(const std::string& html) {
  std::vector<std::vector<std::string>> rows;
  const std::regex row("<tr>(.*?)</tr>"), cell("<t[hd][^>]*>(.*?)</t[hd]>");
  for (auto r = std::sregex_iterator(html.begin(), html.end(), row); r != std::sregex_iterator(); ++r) {
    const std::string inner = (*r)[1];
    rows.emplace_back();
    for (auto c = std::sregex_iterator(inner.begin(), inner.end(), cell); c != std::sregex_iterator(); ++c)
      rows.back().push_back(unescapeHtml((*c)[1]));
  }
  return rows;
}

// The cells of the Markdown table rows (the |---| line left out), '\|' unescaped.
std::vector<std::vector<std::string>> markdownCells(const std::string& md) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(md);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] != '|' || line.rfind("|---", 0) == 0) continue;
    rows.emplace_back();
    std::string cell;
    for (std::size_t i = 1; i < line.size(); ++i) {
      if (line[i] == '\\' && i + 1 < line.size() && line[i + 1] == '|') {
        cell += '|';
        ++i;
      } else if (line[i] == '|') {
        rows.back().push_back(cell.substr(1, cell.size() - 2));  // " text " -> "text"
        cell.clear();
      } else {
        cell += line[i];
      }
    }
  }
  return rows;
}

}  // namespace

TEST_CASE("document: a table renders the same cells in HTML and Markdown") {
  const std::vector<std::string> head = {"series", "a|b", "<x> & \"y\""};
  const std::vector<std::vector<std::string>> rows = {{"MSP", "0.59 ± 0.002 (n=3)", "missing"},
                                                      {"pipe | in cell", "-0.01 ± 0.0016 (*)", ""}};
  study::Document doc("t");
  doc.table(head, rows);
  std::vector<std::vector<std::string>> expected = {head};
  expected.insert(expected.end(), rows.begin(), rows.end());
  CHECK(htmlCells(study::renderHtml(doc)) == expected);
  CHECK(markdownCells(study::renderMarkdown(doc)) == expected);
  // Cells reporting a problem are highlighted in HTML only.
  const std::string html = study::renderHtml(doc);
  CHECK(html.find("<td class=\"flag\">missing</td>") != std::string::npos);
  CHECK(html.find("<td class=\"flag\">-0.01 ± 0.0016 (*)</td>") != std::string::npos);
  CHECK(html.find("<td>MSP</td>") != std::string::npos);
}

TEST_CASE("document: blocks come out once each, in order, in both renderings") {
  study::Document doc("Report <1>");
  doc.heading(1, "Report <1>");
  doc.paragraph("first & only");
  doc.table({"h"}, {});  // no rows: "(no data)"
  doc.bullets({"one", "two"});
  doc.figure({"fig_a", "drawn", "<svg>A</svg>", ""});
  doc.figure({"fig_b", "failed one", "", "gnuplot failed: exited with status 3"});
  const std::string md = study::renderMarkdown(doc);
  const std::string html = study::renderHtml(doc);
  CHECK(md.rfind("# Report <1>\n\nfirst & only\n\n(no data)\n\n- one\n- two\n\n", 0) == 0);
  CHECK(md.find("![drawn](figures/fig_a.svg)") != std::string::npos);
  CHECK(md.find("*Figure fig_b: failed one* (not drawn: gnuplot failed: exited with status 3; data in "
                "[figures/fig_b.csv](figures/fig_b.csv), script figures/fig_b.gp)") != std::string::npos);
  CHECK(html.find("<title>Report &lt;1&gt;</title>") != std::string::npos);
  const std::vector<std::string> inOrder = {"<h1>Report &lt;1&gt;</h1>", "<p>first &amp; only</p>", "<p>(no data)</p>",
                                            "<li>one</li>", "<figure><svg>A</svg>",
                                            "(not drawn: gnuplot failed: exited with status 3; data in figures/fig_b.csv)"};
  std::size_t at = 0;
  for (const std::string& s : inOrder) {
    const std::size_t p = html.find(s);
    CHECK(p != std::string::npos);
    CHECK(p >= at);
    CHECK(html.find(s, p + 1) == std::string::npos);
    at = p;
  }
}

TEST_CASE("csv: metadata skipped, header named, non-numbers NaN, ragged rows dropped") {
  const auto t = study::parseCsv("# seed: 1\ny,phi\n0,0.5\n\n1,x\n2,0.6,9\n# end\n3,0.7\n");
  REQUIRE(t);
  CHECK(t->columns == std::vector<std::string>{"y", "phi"});
  REQUIRE(t->rows.size() == 3);
  CHECK(t->rows[0] == std::vector<double>{0.0, 0.5});
  CHECK(std::isnan(t->rows[1][1]));
  CHECK(t->rows[2] == std::vector<double>{3.0, 0.7});
  CHECK_FALSE(study::parseCsv("y\n1\n2\n"));    // one column: not a profile
  CHECK_FALSE(study::parseCsv("# only\ny,phi\n"));  // no row
  CHECK_FALSE(study::readCsv("/nonexistent/phi_y.csv"));
}

TEST_CASE("process: arguments and working directory reach the program as they are, no shell") {
  const fs::path dir = awkwardDir("process");
  const std::string arg = "it's \"quoted\" $HOME; echo no `id` > x & |";
  const fs::path out = dir / "out put.txt";
  study::ProcessResult r = study::runProcess({"printf", "%s\\n", arg}, {{}, out, {}});
  CHECK(r.ok());
  CHECK(slurp(out) == arg + "\n");
  CHECK_FALSE(fs::exists(dir / "x"));
  r = study::runProcess({"pwd"}, {dir, out, {}});
  CHECK(r.ok());
  CHECK(slurp(out) == fs::canonical(dir).string() + "\n");
  // Exit status and failure to start.
  r = study::runProcess({"sh", "-c", "echo oops >&2; exit 3"}, {{}, out, {}});
  CHECK(r.started);
  CHECK(r.exitCode == 3);
  CHECK_FALSE(r.ok());
  CHECK(slurp(out) == "oops\n");
  CHECK(r.describe({}) == "exited with status 3");
  r = study::runProcess({(dir / "no such program").string()});
  CHECK_FALSE(r.started);
  CHECK(r.describe({}).find("no such program") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("process: a program that outlives its timeout is killed") {
  const auto t0 = std::chrono::steady_clock::now();
  const study::ProcessResult r = study::runProcess({"sleep", "20"}, {{}, {}, std::chrono::milliseconds(150)});
  CHECK(r.timedOut);
  CHECK_FALSE(r.ok());
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(5));
  CHECK(r.describe(std::chrono::milliseconds(150)) == "timed out after 0.15 s (killed)");
}

TEST_CASE("figures: a gnuplot that fails, times out or writes an empty SVG fails that figure, by name") {
  const fs::path dir = awkwardDir("figures");
  struct Case {
    std::string body, expect;
  };
  const std::vector<Case> cases = {
      {"echo 'line 0: undefined variable: phi' >&2; exit 3", "exited with status 3: line 0: undefined variable: phi"},
      {": > \"${1%.gp}.svg\"", "fig.svg is empty"},
      {"printf '<svg>' > \"${1%.gp}.svg\"", "fig.svg is not a complete SVG"},
      {"exit 0", "no fig.svg written"},
      {"exec sleep 20", "timed out after 0.2 s (killed)"},
  };
  for (const Case& c : cases) {
    INFO(c.body);
    const fs::path figures = dir / "figures";
    fs::remove_all(figures);
    study::FigureWriter w(figures, fakeGnuplot(dir, c.body), std::chrono::milliseconds(200));
    REQUIRE(w.available());
    const study::Figure f = w.draw(tinyPlot("fig"));
    CHECK(f.svg.empty());
    CHECK(f.error.find(c.expect) != std::string::npos);
    REQUIRE(w.errors().size() == 1);
    CHECK(w.errors()[0].rfind("figure fig: gnuplot failed: ", 0) == 0);
    CHECK_FALSE(fs::exists(figures / "fig.svg"));  // a broken drawing is not kept
    CHECK(fs::exists(figures / "fig.log"));         // gnuplot's output is
    CHECK(fs::exists(figures / "fig.csv"));
    CHECK(fs::exists(figures / "fig.gp"));
  }
  // A gnuplot that cannot be started is not used: no figure fails, none is drawn.
  study::FigureWriter none(dir / "figures", dir / "no gnuplot here");
  CHECK_FALSE(none.available());
  CHECK(none.draw(tinyPlot("fig")).error.empty());
  CHECK(none.errors().empty());
  fs::remove_all(dir);
}

TEST_CASE("figures: gnuplot runs in the figures folder with the script's name, whatever the path") {
  const fs::path dir = awkwardDir("paths");
  const fs::path figures = dir / "fig ures 'x'";
  // The fake records its working directory and arguments, then draws.
  const fs::path fake = fakeGnuplot(
      dir, "pwd > args.txt; printf '%s\\n' \"$@\" >> args.txt; printf '<?xml version=\"1.0\"?>\\n<svg>ok</svg>\\n' > "
           "\"${1%.gp}.svg\"");
  study::FigureWriter w(figures, fake);
  const study::Figure f = w.draw(tinyPlot("phi_vs_invW"));
  CHECK(f.error.empty());
  CHECK(f.svg == "<svg>ok</svg>\n");  // without the XML declaration
  CHECK(w.errors().empty());
  CHECK(slurp(figures / "args.txt") == fs::canonical(figures).string() + "\nphi_vs_invW.gp\n");
  CHECK_FALSE(fs::exists(figures / "phi_vs_invW.log"));
  // The real gnuplot, when installed, draws in that folder too.
  study::FigureWriter real(figures, "gnuplot");
  if (real.available()) {
    const study::Figure g = real.draw(tinyPlot("real"));
    CHECK(g.error.empty());
    CHECK(g.svg.rfind("<svg", 0) == 0);
    CHECK(fs::file_size(figures / "real.svg") > 0);
  }
  fs::remove_all(dir);
}
