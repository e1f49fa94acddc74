// The report's HTML in a real browser (headless Chromium): every figure of a synthetic study's
// report must render, each one an inline SVG that lays out at a visible size with lines and text
// drawn in it. A copy of the page gets a short script that counts the figures and the broken ones
// and writes the counts into the page's title; Chromium's --dump-dom prints the page after its
// scripts ran. The same check on a copy with one SVG removed and another emptied must see both,
// so the check cannot pass by seeing nothing.
//
// Tagged [browser] (ctest label "browser": ctest -L browser). Needs chromium (Debian: apt-get
// install chromium; CONFPACK_CHROMIUM names another binary) and gnuplot; without either it warns
// and passes, and the README's test line installs both.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "study/process.hpp"
#include "study/report.hpp"
#include "study/sweep.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/scratch.hpp"
#include "tests/support/study_stubs.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::slurp;
using nlohmann::json;

namespace {

// The browser, or empty: CONFPACK_CHROMIUM, else chromium or chromium-browser in PATH.
fs::path findChromium() {
  if (const char* given = std::getenv("CONFPACK_CHROMIUM"); given && *given) return given;
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');)
    for (const char* name : {"chromium", "chromium-browser"}) {
      const fs::path p = fs::path(dir) / name;
      if (::access(p.c_str(), X_OK) == 0) return p;
    }
  return {};
}

// A study of 12 runs with every kind of figure the report draws: phi and Z against d_L/W with
// their fits and a reference mark, lambda_L, the profiles phi(y) and Z(y), two backends.
void makeStudy(const fs::path& dir) {
  const study::SweepSpec spec = study::parseSweepSpec(json::parse(R"({
    "name": "browser", "base": { "box": { "length_x": 6, "height": 4 } }, "biperiodic_width": 12,
    "vary": { "width": [4, 8, "biperiodic"], "replicas": 2, "backend": ["nscd", "bullet"] } })"));
  auto runner = [](const core::RunConfig& cfg, const fs::path& runDir, const compaction::Deposit&,
                   const study::RunProgressFn&) {
    const double s = 0.002 * static_cast<double>(cfg.seed);
    const double w = cfg.box.periodicY ? 1e9 : cfg.box.width;
    const json r = {{"solid_fraction", 0.64 - 0.5 / w + s},
                    {"mean_size", 1.0},
                    {"coordination", {{"Z", 6.0 - 1.2 / w + s}}},
                    {"profile_fit", {{"lambda_L", 1.0 + s}, {"lambda_L_over_d_avg", 1.0 + s}}},
                    {"interpenetration_percent", {{"exact", 0.01}}},
                    {"equilibrium", {{"reached", true}}},
                    {"timing", {{"wall_s", 1.0}, {"steps", 100}}}};
    std::ofstream(runDir / "result.json") << r.dump();
    std::ofstream phi(runDir / "phi_y.csv"), z(runDir / "z_y.csv");
    phi << "y,phi\n";
    z << "y,Z,simple\n";
    // A layering decaying over 1 d_L, for the lambda_L figures (study/report_lambda.hpp).
    for (int i = 0; i < 100; ++i) {
      const double y = 0.02 * (i + 0.5);
      phi << y << ','
          << (1.0 - std::exp(-y / 0.08)) * (0.6 + 0.2 * std::exp(-y) * std::cos(3.3 * (2.0 * y - 1.0))) + s * 0.01
          << '\n';
    }
    for (int i = 0; i < 20; ++i) z << 0.25 * i << ',' << 5.5 + 0.02 * i << ',' << 5.0 << '\n';
    return r;
  };
  study::SweepOptions o;
  o.quiet = true;
  study::runSweep(spec, dir, o, runner, testing::oneGrainDeposit);
}

// Appended before </body>: counts the figures, the ones the report could not draw (p.fig), and
// the broken ones: a figure without an inline SVG, an SVG laid out smaller than 100 px, one whose
// content has no extent, or one without lines or without text; and any <img> that did not load.
constexpr const char* kCheckScript = R"(<script>
(function () {
  var figures = document.querySelectorAll('figure');
  var broken = [];
  for (var i = 0; i < figures.length; ++i) {
    var f = figures[i], svg = f.querySelector('svg'), why = '';
    if (!svg) {
      why = 'no svg';
    } else {
      var r = svg.getBoundingClientRect(), b = null;
      try { b = svg.getBBox(); } catch (e) {}
      var lines = svg.querySelectorAll('path, polyline, polygon, line, rect, circle, use').length;
      var texts = svg.querySelectorAll('text').length;
      if (r.width < 100 || r.height < 100) why = 'laid out at ' + r.width + 'x' + r.height;
      else if (!b || b.width < 10 || b.height < 10) why = 'nothing drawn';
      else if (lines === 0 || texts === 0) why = lines + ' lines, ' + texts + ' texts';
    }
    if (why) broken.push('figure ' + i + ': ' + why);
  }
  var images = document.querySelectorAll('img');
  for (var j = 0; j < images.length; ++j)
    if (!images[j].complete || images[j].naturalWidth === 0) broken.push('img ' + images[j].src + ' not loaded');
  document.title = 'confpack-check figures=' + figures.length + ' notdrawn=' +
                   document.querySelectorAll('p.fig').length + ' broken=' + broken.length + ' ' + broken.join('; ');
})();
</script>
)";

struct PageCheck {
  int figures = -1, notDrawn = -1, broken = -1;
  std::string detail;  // the title, or what chromium said
};

// Loads `html` (with the check script added) in headless Chromium and reads the counts back.
PageCheck checkInBrowser(const fs::path& chromium, const std::string& html, const fs::path& dir,
                         const std::string& name) {
  const std::size_t body = html.rfind("</body>");
  REQUIRE(body != std::string::npos);
  const fs::path page = dir / (name + ".html");
  std::ofstream(page) << html.substr(0, body) << kCheckScript << html.substr(body);
  const fs::path profile = dir / (name + "-profile");
  const fs::path out = dir / (name + ".out");
  // The flags keep a closed network from stalling it: no lookups, no component or sync requests.
  const study::ProcessResult r = study::runProcess(
      {chromium.string(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
       "--disable-background-networking", "--disable-component-update", "--disable-sync",
       "--user-data-dir=" + profile.string(), "--dump-dom", "file://" + page.string()},
      {dir, out, std::chrono::seconds(60)});
  PageCheck c;
  c.detail = slurp(out);
  INFO("chromium: " << r.describe(std::chrono::seconds(60)));
  REQUIRE(r.ok());
  std::smatch m;
  static const std::regex title("<title>confpack-check figures=(\\d+) notdrawn=(\\d+) broken=(\\d+)([^<]*)</title>");
  if (std::regex_search(c.detail, m, title)) {
    c.figures = std::stoi(m[1]);
    c.notDrawn = std::stoi(m[2]);
    c.broken = std::stoi(m[3]);
    c.detail = m[4];
  }
  return c;
}

// `html` with the n-th inline SVG (0-based) changed by `edit`, given the SVG's text.
template <class Edit>
std::string editSvg(std::string html, int n, Edit edit) {
  std::size_t at = 0;
  for (int i = 0; i <= n; ++i) {
    at = html.find("<figure><svg", at + 1);
    REQUIRE(at != std::string::npos);
  }
  at += std::string("<figure>").size();
  const std::size_t end = html.find("</svg>", at) + std::string("</svg>").size();
  return html.replace(at, end - at, edit(html.substr(at, end - at)));
}

}  // namespace

TEST_CASE("report: every figure renders in headless Chromium, and a removed or emptied SVG is caught", "[browser]") {
  const fs::path chromium = findChromium();
  if (chromium.empty()) {
    WARN(
        "chromium not found (apt-get install chromium, or set CONFPACK_CHROMIUM): the report was not checked in a "
        "browser");
    return;
  }
  const fs::path dir = testing::freshDir("report_browser");
  makeStudy(dir / "study");
  study::ReportOptions o;
  o.reference = study::parseReferenceValues(
      json::parse(R"({"families": {"MSP": {"phi_bulk": {"value": 0.64, "uncertainty": 0.01, "citation": "RCP"},
                      "C": {"value": 0.5, "uncertainty": 0.1, "citation": "example"}}}})"),
      "reference.json");
  const study::ReportSummary s = study::writeReport(dir / "study", dir / "report", o);
  if (!s.gnuplotUsed) {
    WARN("gnuplot not found (apt-get install gnuplot-nox): the report has no figures to check in a browser");
    fs::remove_all(dir);
    return;
  }
  REQUIRE(s.figureErrors.empty());
  // phi and Z against d_L/W, lambda_L against x_S and C, 2 profiles of phi(y), 2 of Z(y) at least.
  REQUIRE(s.figures >= 6);
  const std::string html = slurp(s.html);

  const PageCheck whole = checkInBrowser(chromium, html, dir, "whole");
  INFO("page: " << whole.detail);
  CHECK(whole.figures == static_cast<int>(s.figures));
  CHECK(whole.notDrawn == 0);
  CHECK(whole.broken == 0);

  // The same page with the first SVG removed and the content of the third emptied.
  std::string damaged = editSvg(html, 0, [](const std::string&) { return std::string(); });
  damaged = editSvg(damaged, 1, [](const std::string& svg) {
    const std::size_t open = svg.find('>') + 1;
    return svg.substr(0, open) + "</svg>";
  });
  const PageCheck broken = checkInBrowser(chromium, damaged, dir, "damaged");
  INFO("damaged page: " << broken.detail);
  CHECK(broken.figures == static_cast<int>(s.figures));
  CHECK(broken.broken == 2);
  CHECK_THAT(broken.detail, Catch::Contains("figure 0: no svg") && Catch::Contains("figure 2: nothing drawn"));
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}
