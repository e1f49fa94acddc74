// The report's document model (study/report_document.hpp): one set of blocks, two renderings that
// say the same thing.
#include <catch2/catch.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "study/report_document.hpp"

using namespace confpack;

namespace {

std::string unescapeHtml(std::string s) {
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&amp;", "&"}}) {
    for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
      s.replace(p, from.size(), to);
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
  const std::vector<std::string> inOrder = {
      "<h1>Report &lt;1&gt;</h1>", "<p>first &amp; only</p>",
      "<p>(no data)</p>",          "<li>one</li>",
      "<figure><svg>A</svg>",      "(not drawn: gnuplot failed: exited with status 3; data in figures/fig_b.csv)"};
  std::size_t at = 0;
  for (const std::string& s : inOrder) {
    const std::size_t p = html.find(s);
    CHECK(p != std::string::npos);
    CHECK(p >= at);
    CHECK(html.find(s, p + 1) == std::string::npos);
    at = p;
  }
}

TEST_CASE("document: a link is a Markdown link and an HTML anchor, its target encoded, other brackets text") {
  CHECK(study::link("r0007", "../runs/r0007") == "[r0007](../runs/r0007)");
  CHECK(study::link("run", "../my study/runs/r(1)") == "[run](../my%20study/runs/r%281%29)");
  study::Document doc("t");
  doc.paragraph("See " + study::link("tables/a.csv", "tables/a.csv") + " and W [d_L] (not a link) & more.");
  doc.table({"run", "x_S [%]"}, {{study::link("r0000", "../runs/r0000"), "0"}});
  const std::string md = study::renderMarkdown(doc);
  const std::string html = study::renderHtml(doc);
  CHECK(md.find("See [tables/a.csv](tables/a.csv) and W [d_L] (not a link) & more.") != std::string::npos);
  CHECK(md.find("| [r0000](../runs/r0000) | 0 |") != std::string::npos);
  CHECK(html.find("<p>See <a href=\"tables/a.csv\">tables/a.csv</a> and W [d_L] (not a link) &amp; more.</p>") !=
        std::string::npos);
  CHECK(html.find("<td><a href=\"../runs/r0000\">r0000</a></td>") != std::string::npos);
  CHECK(html.find("<th>x_S [%]</th>") != std::string::npos);
}
