// The report's figures (study/report_figures.hpp) with a fake gnuplot that fails in each way it
// can, and with the real one when it is installed.
#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>

#include "study/report_figures.hpp"
#include "tests/support/awkward_dir.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::awkwardDir;
using confpack::testing::slurp;

namespace {

// An executable shell script standing in for gnuplot: `--version` succeeds, anything else runs body.
fs::path fakeGnuplot(const fs::path& dir, const std::string& body) {
  const fs::path p = dir / "fake gnuplot's \"bin\"";
  std::ofstream(p) << "#!/bin/sh\nif [ \"$1\" = --version ]; then echo 'gnuplot 0.0 fake'; exit 0; fi\n"
                   << body << "\n";
  fs::permissions(p, fs::perms::owner_all);
  return p;
}

study::Plot tinyPlot(const std::string& stem) {
  study::Plot p{stem, "a tiny plot", "x", "y", {}, {}, false};
  p.series.push_back({"line", 1, false, true, {{{0.0, 1.0, 0.0}}, {{1.0, 2.0, 0.1}}}, true});
  return p;
}

}  // namespace

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
    CHECK(fs::exists(figures / "fig.log"));        // gnuplot's output is
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
      dir,
      "pwd > args.txt; printf '%s\\n' \"$@\" >> args.txt; printf '<?xml version=\"1.0\"?>\\n<svg>ok</svg>\\n' > "
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
