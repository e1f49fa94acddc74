// The report's compared setting (`confpack report --compare KEY`): runs that differ in a nested
// configuration key are put side by side by its two values, each value's numbers its own runs'
// means, the families formed from every other axis; a key with one or three values, missing from
// a run, or one the families are told apart by is refused by name; comparing the backend by name
// gives the report it gives unasked.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "study/csv_table.hpp"
#include "study/report.hpp"
#include "study/report_compare.hpp"
#include "study/sweep.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/study_stubs.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::slurp;
using nlohmann::json;

namespace {

// Replica offsets delta (s - 2) for seeds 1, 2, 3: each configuration's mean is exactly its law's.
constexpr double kDelta = 0.002;

// phi = phi_bulk - C/W by nscd's solver: mprgp 0.64 and 0.5, nlgs 0.62 and 0.2 (the same at no
// width the study has); Z = 6 - 1.2/W for both; the interpenetration 0.01 % and 0.05 %.
json solverResult(const core::RunConfig& cfg) {
  const bool mprgp = cfg.backendOptions.value("solver", "") == "mprgp";
  const double phiBulk = mprgp ? 0.64 : 0.62, c = mprgp ? 0.5 : 0.2;
  const double offset = kDelta * (static_cast<double>(cfg.seed) - 2.0);
  const double inverseWidth = cfg.box.periodicY ? 0.0 : 1.0 / cfg.box.width;
  return {{"n_grains", 100},
          {"solid_fraction", phiBulk - c * inverseWidth + offset},
          {"coordination", {{"Z", 6.0 - 1.2 * inverseWidth + offset}}},
          {"interpenetration_percent", {{"exact", mprgp ? 0.01 : 0.05}}},
          {"equilibrium", {{"reached", true}}},
          {"timing", {{"wall_s", mprgp ? 2.0 : 3.0}, {"steps", 100}}}};
}

// A finished sweep folder of `doc`'s runs, each with the result `result` gives it.
fs::path makeStudy(const std::string& name, const json& doc, json (*result)(const core::RunConfig&)) {
  const fs::path dir =
      fs::temp_directory_path() / ("confpack_test_report_compare_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  auto runner = [&](const core::RunConfig& cfg, const fs::path& runDir, const compaction::Deposit&,
                    const study::RunProgressFn&) {
    const json r = result(cfg);
    std::ofstream(runDir / "result.json") << r.dump();
    return r;
  };
  study::SweepOptions o;
  o.quiet = true;
  study::runSweep(study::parseSweepSpec(doc), dir, o, runner, testing::oneGrainDeposit);
  return dir;
}

// The cells of the first Markdown table row at or after `from` that starts with `prefix`.
std::vector<std::string> rowCells(const std::string& md, const std::string& prefix, std::size_t from = 0) {
  const std::size_t at = md.find(prefix, from);
  if (at == std::string::npos) return {};
  std::vector<std::string> cells;
  std::istringstream line(md.substr(at + 1, md.find('\n', at) - at - 1));
  for (std::string cell; std::getline(line, cell, '|');)
    cells.push_back(cell.substr(1, cell.size() >= 2 ? cell.size() - 2 : 0));
  return cells;
}

std::size_t column(const study::CsvTable& t, const std::string& name) {
  const auto it = std::find(t.columns.begin(), t.columns.end(), name);
  REQUIRE(it != t.columns.end());
  return static_cast<std::size_t>(it - t.columns.begin());
}

// The message compareSetting refuses `key` with over the runs of sweep document `doc`.
std::string refusal(const std::string& key, const json& doc) {
  try {
    study::compareSetting(key, study::expandRuns(study::parseSweepSpec(doc)));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

const json kSolvers = json::parse(R"({
  "name": "solvers", "base": { "box": { "length_x": 6, "height": 4 } }, "biperiodic_width": 12,
  "vary": { "width": [4, 10, 20, "biperiodic"], "replicas": 3, "backend": ["nscd"],
            "backend_options.solver": ["mprgp", "nlgs"] } })");

}  // namespace

TEST_CASE("report --compare a nested key: its two values side by side, each with its own runs' numbers") {
  const fs::path dir = makeStudy("solver", kSolvers, solverResult);
  study::ReportOptions options;
  options.gnuplot.clear();
  options.compare = "backend_options.solver";
  const std::string md = slurp(study::writeReport(dir, dir / "report", options).markdown);
  CHECK_THAT(md, Catch::Contains("This report compares the runs by backend_options.solver: mprgp against nlgs"));
  // The summary: a row per family and value, the fits of that value's runs alone.
  const std::size_t summaryAt = md.find("## Summary: the results per family and value of solver");
  REQUIRE(summaryAt != std::string::npos);
  CHECK_THAT(md, Catch::Contains("| family | solver | runs at equilibrium / total |"));
  const auto mprgp = rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | mprgp |", summaryAt);
  const auto nlgs = rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | nlgs |", summaryAt);
  REQUIRE(mprgp.size() > 8);
  REQUIRE(nlgs.size() > 8);
  CHECK(mprgp[2] == "12 / 12");
  CHECK_THAT(mprgp[5], Catch::StartsWith("0.6400 ± "));  // phi_bulk
  CHECK_THAT(mprgp[6], Catch::StartsWith("0.500 ± "));   // C
  CHECK_THAT(nlgs[5], Catch::StartsWith("0.6200 ± "));
  CHECK_THAT(nlgs[6], Catch::StartsWith("0.200 ± "));
  // The verdict: mprgp against nlgs, as nscd against Bullet.
  const std::size_t verdictAt = md.find("## Verdict: mprgp against nlgs");
  REQUIRE(verdictAt != std::string::npos);
  CHECK(md.find("## Cross-solver verdict") == std::string::npos);
  CHECK(md.find("| family | quantity | mprgp | nlgs | mprgp − nlgs | combined SE |", verdictAt) != std::string::npos);
  const auto phiBulk = rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | phi_bulk |", verdictAt);
  REQUIRE(phiBulk.size() == 7);
  CHECK(phiBulk[4] == "+0.02");
  CHECK(phiBulk[6] == "yes: differ (*)");
  CHECK_THAT(md, Catch::Contains("mprgp and nlgs differ on phi_bulk by +0.02 ± "));
  CHECK_THAT(md, Catch::Contains("mprgp and nlgs agree on Z_bulk within 2 standard errors"));
  CHECK_THAT(md, Catch::Contains("mprgp and nlgs differ on interpenetration by -0.04"));
  // The backend is the same for every run: no family, column or series is named by it.
  CHECK(md.find("| nscd |") == std::string::npos);
  CHECK(md.find("backend = nscd") == std::string::npos);
  // The run table still says each run's value; the cost is per value.
  CHECK_THAT(md, Catch::Contains("MSP xS=0 W=4 mu=0 s1 nscd solver=nlgs"));
  CHECK_THAT(md, Catch::Contains("| solver | finished runs | total wall [s] |"));
  CHECK(rowCells(md, "| nlgs | 12 |", md.find("## Cost")).at(2) == "36");
  // tables/: the per-value columns and their difference, each the mean of that value's replicas.
  const auto phi = study::readCsv(dir / "report" / "tables" / "solid_fraction.csv");
  REQUIRE(phi);
  CHECK(std::find(phi->columns.begin(), phi->columns.end(), "nscd_mean") == phi->columns.end());
  CHECK(std::find(phi->columns.begin(), phi->columns.end(), "backend_options.solver") == phi->columns.end());
  bool found = false;
  for (std::size_t i = 0; i < phi->rows.size(); ++i)
    if (phi->rows[i][column(*phi, "W")] == 4.0 && phi->rows[i][column(*phi, "biperiodic")] == 0.0) {
      found = true;
      CHECK(phi->rows[i][column(*phi, "mprgp_mean")] == Approx(0.64 - 0.5 / 4));
      CHECK(phi->rows[i][column(*phi, "nlgs_mean")] == Approx(0.62 - 0.2 / 4));
      CHECK(phi->rows[i][column(*phi, "mprgp_n")] == 3.0);
      CHECK(phi->rows[i][column(*phi, "mprgp_minus_nlgs")] == Approx(-0.055));
    }
  CHECK(found);
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}

TEST_CASE("report --compare a key both backends have: the backend is part of each family") {
  const fs::path dir = makeStudy(
      "time_limit", json::parse(R"({
    "name": "limits", "base": { "box": { "length_x": 6, "height": 4 } },
    "vary": { "width": ["biperiodic"], "backend": ["nscd", "bullet"], "compaction.time_limit": [5, 10] } })"),
      [](const core::RunConfig& cfg) -> json {
        return {{"solid_fraction", 0.6 + cfg.compaction.timeLimit / 1000.0}, {"equilibrium", {{"reached", true}}}};
      });
  const std::vector<study::SweepRun> runs = study::readRunTable(dir);
  const study::ComparedSetting by = study::compareSetting("compaction.time_limit", runs);
  CHECK(by.column == "time_limit");
  CHECK(by.familySettings(runs) == std::vector<std::string>{"backend"});
  study::ReportOptions options;
  options.gnuplot.clear();
  options.compare = "compaction.time_limit";
  const std::string md = slurp(study::writeReport(dir, dir / "report", options).markdown);
  for (const std::string backend : {"nscd", "bullet"}) {
    const auto row = rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0, backend = " + backend + " | phi |",
                              md.find("## Verdict: 5 against 10"));
    REQUIRE(row.size() == 7);
    CHECK(row[2] == "0.605 (1 run)");
    CHECK(row[3] == "0.61 (1 run)");
  }
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}

TEST_CASE("report --compare refuses a key with one or three values, missing from a run, or a family's own") {
  json one = kSolvers, three = kSolvers;
  one["vary"]["backend_options.solver"] = {"mprgp"};
  three["vary"]["backend_options.solver"] = {"mprgp", "nlgs", "ipm"};
  CHECK(refusal("backend_options.solver", one) ==
        "--compare backend_options.solver: the runs have 1 value of backend_options.solver (mprgp); a comparison "
        "needs exactly two");
  CHECK(refusal("backend_options.solver", three) ==
        "--compare backend_options.solver: the runs have 3 values of backend_options.solver (mprgp, nlgs, ipm); a "
        "comparison needs exactly two");
  CHECK(refusal("backend", kSolvers) ==
        "--compare backend: the runs have 1 value of backend (nscd); a comparison needs exactly two");
  // Bullet's runs have no nscd solver: the first is named.
  const json mixed = json::parse(R"({
    "name": "mixed", "base": { "box": { "length_x": 6, "height": 4 } },
    "groups": [ { "width": [10], "backend": ["nscd"], "backend_options.solver": ["mprgp", "nlgs"] },
                { "width": [10], "backend": ["bullet"] } ] })");
  CHECK(refusal("backend_options.solver", mixed) ==
        "--compare backend_options.solver: run r0002 has no backend_options.solver in its configuration (1 of the 3 "
        "runs lack it)");
  CHECK(refusal("backend_options.theta", kSolvers) ==
        "--compare backend_options.theta: no run's configuration has backend_options.theta (a run's config.json "
        "shows every key its configuration has)");
  CHECK_THAT(refusal("box", kSolvers), Catch::StartsWith("--compare box: box is a section of the run configuration ("));
  CHECK_THAT(refusal("walls.friction", kSolvers),
             Catch::StartsWith("--compare walls.friction: the report's families are told apart by walls.friction"));
  // The report refuses as the check does, before it writes anything.
  const fs::path dir = makeStudy("refused", one, solverResult);
  study::ReportOptions options;
  options.gnuplot.clear();
  options.compare = "backend_options.solver";
  CHECK_THROWS_WITH(study::writeReport(dir, dir / "report", options),
                    Catch::Contains("the runs have 1 value of backend_options.solver (mprgp)"));
  CHECK_FALSE(fs::exists(dir / "report"));
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}

TEST_CASE("report --compare backend is the report without --compare, settled series included") {
  const fs::path dir = makeStudy("backend", json::parse(R"({
    "name": "backends", "base": { "box": { "length_x": 6, "height": 4 } },
    "vary": { "width": [5, 10], "replicas": 2, "backend": ["nscd", "bullet"] } })"),
                                 solverResult);
  // A settle for each of Bullet's runs, where a sweep's settle_with keeps it.
  for (const auto& e : fs::directory_iterator(dir / "runs")) {
    const json config = json::parse(slurp(e.path() / "config.json"));
    if (config.value("backend", "") != "bullet") continue;
    fs::create_directories(e.path() / study::kSettledFolder);
    std::ofstream(e.path() / study::kSettledFolder / "result.json")
        << json{{"solid_fraction", 0.6}, {"equilibrium", {{"reached", true}}}}.dump();
  }
  study::ReportOptions options;
  options.gnuplot.clear();
  const auto unasked = study::writeReport(dir, dir / "unasked", options);
  options.compare = "backend";
  const auto asked = study::writeReport(dir, dir / "asked", options);
  // The page says when it was written, to the minute: that line aside, the two are the same.
  const auto withoutDate = [](std::string text) {
    const std::size_t at = text.find(" Written ");
    return at == std::string::npos ? text : text.erase(at, text.find(" by confpack", at) - at);
  };
  const std::string md = slurp(unasked.markdown);
  CHECK_THAT(md, Catch::Contains("## Cross-solver verdict"));
  CHECK_THAT(md, Catch::Contains("bullet_settled"));
  CHECK(withoutDate(slurp(asked.markdown)) == withoutDate(md));
  CHECK(withoutDate(slurp(asked.html)) == withoutDate(slurp(unasked.html)));
  for (const auto& e : fs::directory_iterator(dir / "unasked" / "tables"))
    CHECK(slurp(dir / "asked" / "tables" / e.path().filename()) == slurp(e.path()));
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}
