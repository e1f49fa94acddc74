// `confpack reproduce` with the real binary and real physics: the tiny scale end to end. The study
// definitions (the library's reproductionSweep) are tested in tests/study/test_reproduce.cpp.
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "study/sweep.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::ConfpackSession;
using confpack::testing::slurp;

TEST_CASE("reproduce --scale tiny: the whole chain to a report") {
  const ConfpackSession s("cmd_reproduce_tiny");
  const fs::path& dir = s.dir;
  const auto t0 = std::chrono::steady_clock::now();
  const auto first = s.run("reproduce --scale tiny --out tiny --jobs 2");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO("stderr: " << first.err);
  REQUIRE(first.code == 0);
  WARN("reproduce --scale tiny took " << seconds << " s");
  const std::string md = slurp(dir / "tiny" / "report" / "report.md");
  const std::string html = slurp(dir / "tiny" / "report" / "report.html");
  CHECK(md.find("# confpack study report: tiny") != std::string::npos);
  // The run table links each run's folder from the report's final place (it was written staged).
  CHECK(md.find("| [r0005](../runs/r0005) |") != std::string::npos);
  CHECK(fs::is_directory(dir / "tiny" / "report" / "../runs/r0005"));
  // Every quantity per configuration is in tables/, not on the page.
  CHECK(slurp(dir / "tiny" / "report" / "tables" / "solid_fraction.csv").find("\nsolid_fraction,") !=
        std::string::npos);
  CHECK(md.find("[tables/solid_fraction.csv](tables/solid_fraction.csv)") != std::string::npos);
  CHECK(md.find("### solid_fraction") == std::string::npos);
  CHECK(md.find("nscd − bullet") != std::string::npos);
  CHECK(html.find("</html>") != std::string::npos);
  for (int i = 0; i < 6; ++i) {
    char name[8];
    std::snprintf(name, sizeof name, "r%04d", i);
    CHECK(study::runStatus(dir / "tiny" / "runs" / name) == study::RunStatus::Done);
  }
  // Running it again finds everything done and only rewrites the report.
  const auto again = s.run("reproduce --scale tiny --out tiny");
  REQUIRE(again.code == 0);
  CHECK(again.out.find("0 finished now, 6 earlier") != std::string::npos);
}
