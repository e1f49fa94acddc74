// Study report: statistics over replicas, backend differences, the phi(W) fit on synthetic data
// with known phi_bulk and C, missing/failed runs shown as such, the summary and cross-solver
// verdict that lead the report, the figures before the run table, the run table once with links to
// the run folders, and the per-configuration tables in tables/*.csv, read back.
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "analysis/profile_fit.hpp"
#include "core/build_info.hpp"
#include "study/csv_table.hpp"
#include "study/report.hpp"
#include "study/sweep.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/study_stubs.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using nlohmann::json;

namespace {

using confpack::testing::slurp;

// Synthetic physics: phi = phi_bulk - C / W with a replica offset delta (s - 2) for seeds 1, 2, 3,
// so that the replica mean is exactly on the law and the replica std is exactly delta.
// nscd: phi_bulk = 0.64, C = 0.5; bullet: phi_bulk = 0.63, C = 0.4. Z = 6 - 1.2 / W for both.
// With sameLaw, bullet follows nscd's law for every quantity.
constexpr double kDelta = 0.002;

// The bulk region every synthetic run reports (thickness in d_L and grains), when set, and the
// widths of the study; by default runs give none and the widths are 4, 5, 10, 20 and biperiodic.
struct SyntheticSizes {
  double bulkThickness = 0.0;
  double bulkGrains = 0.0;
  json widths = json::array({4, 5, 10, 20, "biperiodic"});
};
SyntheticSizes gSizes;

json syntheticResult(const core::RunConfig& cfg, bool sameLaw) {
  const bool nscd = sameLaw || cfg.backend == "nscd";
  const double phiBulk = nscd ? 0.64 : 0.63;
  const double c = nscd ? 0.5 : 0.4;
  const double offset = kDelta * (static_cast<double>(cfg.seed) - 2.0);
  const double phi = (cfg.box.periodicY ? phiBulk : phiBulk - c / cfg.box.width) + offset;
  const double z = (cfg.box.periodicY ? 6.0 : 6.0 - 1.2 / cfg.box.width) + offset;
  return {
      {"n_grains", 100},
      {"mean_size", 1.0},
      {"backend", cfg.backend},
      {"seed", cfg.seed},
      {"solid_fraction", phi},
      {"coordination", {{"Z", z}, {"simple", z}, {"double", nullptr}, {"triple", nullptr}, {"rattler_fraction", 0.05}}},
      {"interpenetration_percent", {{"exact", nscd ? 0.01 : 0.2}, {"lattice_min", nullptr}, {"lattice_max", nullptr}}},
      {"equilibrium",
       {{"reached", true}, {"max_force_ratio", 1e-5}, {"max_moment_ratio", 1e-5}, {"max_kinetic_ratio", 1e-9}}},
      // nscd's networks isostatic, Bullet's with one self-stress in ten contacts.
      {"rigidity",
       {{"contacts", 300},
        {"constraints", 300},
        {"degrees_of_freedom", 300},
        {"self_stresses", nscd ? 0 : 30},
        {"self_stresses_between_grains", nscd ? 0 : 20},
        {"mechanisms", nscd ? 3 : 30}}},
      {"anisotropy", 0.1},
      {"nematic", {{"bulk", nullptr}, {"boundary", nullptr}}},
      {"profile_fit",
       {{"phi_bulk", phiBulk},
        {"lambda_L", 1.0 + 0.1 * cfg.population.smallFraction / 10.0},
        {"lambda_L_over_d_avg", (nscd ? 1.25 : 1.5) + offset}}},
      {"timing", {{"wall_s", 1.5}, {"steps", 1000}, {"iterations", 20000}}}};
}

// syntheticResult with gSizes' bulk region, when it has one.
json sizedResult(const core::RunConfig& cfg, bool sameLaw) {
  json r = syntheticResult(cfg, sameLaw);
  if (gSizes.bulkThickness > 0.0)
    r["bulk_region"] = {{"z_low", 3.0}, {"z_high", 3.0 + gSizes.bulkThickness}, {"grains", gSizes.bulkGrains}};
  return r;
}

// phi_y.csv of a run whose walls' layering decays over `lambda` d_L (d_avg = 1), each seed with
// its own small ripple: the seed-averaged fit reads lambda_L/d_avg from it (study/report_lambda.hpp).
void writeLayeredProfile(const fs::path& runDir, const core::RunConfig& cfg, double lambda) {
  analysis::ProfileLaw law;
  law.alpha = 0.08;
  law.phiBulk = 0.6;
  law.beta[0] = 0.2;
  law.gamma[0] = 0.95;
  law.lambda[0] = lambda;
  std::ofstream csv(runDir / "phi_y.csv");
  csv << "# seed " << cfg.seed << "\ny,phi\n";
  const int slices = static_cast<int>(std::min(cfg.box.width, 10.0) / 2.0 / 0.02);
  for (int i = 0; i < slices; ++i) {
    const double y = (i + 0.5) * 0.02;
    csv << y << ',' << law(y) + 1e-4 * std::cos(37.0 * i * cfg.seed) << '\n';
  }
}

// With `settled`, every bullet run also has a settle (RUN/settled/, a sweep's settle_with) that
// follows nscd's law: Bullet's piles, brought to rest, are nscd's.
fs::path makeStudy(const std::string& name, bool withFailures, bool sameLaw = false, std::size_t grainCap = 0,
                   bool settled = false) {
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_report_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  json doc = json::parse(R"({
    "name": "synthetic",
    "base": { "box": { "length_x": 6, "height": 4 } },
    "biperiodic_width": 12,
    "vary": { "replicas": 3, "backend": ["nscd", "bullet"] }
  })");
  doc["vary"]["width"] = gSizes.widths;
  if (grainCap > 0) doc["base"]["deposition"] = {{"grain_cap", grainCap}};
  const study::SweepSpec spec = study::parseSweepSpec(doc);
  auto runner = [&](const core::RunConfig& cfg, const fs::path& runDir, const compaction::Deposit&,
                    const study::RunProgressFn&) {
    // bullet at W = 20 fails for every seed: its cell must read "missing", not vanish.
    if (withFailures && cfg.backend == "bullet" && cfg.box.width == 20.0 && !cfg.box.periodicY)
      throw std::runtime_error("solver diverged");
    json r = sizedResult(cfg, sameLaw);
    // Seed 3 at W = 10 is not at rest: nscd's finisher ran out of steps, Bullet hit its time limit.
    if (withFailures && cfg.box.width == 10.0 && !cfg.box.periodicY && cfg.seed == 3) {
      r["equilibrium"]["reached"] = false;
      if (cfg.backend == "nscd") r["timing"]["stages"] = {{"quasi_static", {{"steps", 3000}}}};
    }
    std::ofstream(runDir / "result.json") << r.dump();
    if (settled && cfg.backend == "bullet") {
      fs::create_directories(runDir / study::kSettledFolder);
      std::ofstream(runDir / study::kSettledFolder / "result.json") << syntheticResult(cfg, true).dump();
    }
    // A layering decaying over 1.25 d_L (nscd) or 1.5 d_L (bullet).
    writeLayeredProfile(runDir, cfg, sameLaw || cfg.backend == "nscd" ? 1.25 : 1.5);
    return r;
  };
  study::SweepOptions o;
  o.quiet = true;
  study::runSweep(spec, dir, o, runner, testing::oneGrainDeposit);
  if (withFailures) {
    // One run interrupted: its folder exists without a done marker.
    fs::remove(dir / "runs" / "r0000" / study::kDoneMarker);
  }
  return dir;
}

// More replicas of makeStudy's nscd runs at one width (seeds 1 to `replicas`), apart as a user
// runs more seeds of one family, their layering decaying over `lambda` d_L; `height` other than 4
// makes them another configuration.
fs::path makeReplicaSweep(const std::string& name, double width, double height, double lambda, int replicas) {
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_report_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  json doc = json::parse(R"({
    "name": "more seeds",
    "base": { "box": { "length_x": 6 } },
    "biperiodic_width": 12,
    "vary": { "backend": ["nscd"] }
  })");
  doc["base"]["box"]["height"] = height;
  doc["vary"]["width"] = {width};
  doc["vary"]["replicas"] = replicas;
  auto runner = [&](const core::RunConfig& cfg, const fs::path& runDir, const compaction::Deposit&,
                    const study::RunProgressFn&) {
    json r = sizedResult(cfg, false);
    std::ofstream(runDir / "result.json") << r.dump();
    writeLayeredProfile(runDir, cfg, lambda);
    return r;
  };
  study::SweepOptions o;
  o.quiet = true;
  study::runSweep(study::parseSweepSpec(doc), dir, o, runner, testing::oneGrainDeposit);
  return dir;
}

// A table of the report's tables/ folder, read back with the CSV reader.
study::CsvTable readTable(const fs::path& reportDir, const std::string& file) {
  auto t = study::readCsv(reportDir / "tables" / file);
  REQUIRE(t);
  return *t;
}

// The value of `column` in the row of `key` at width W (confined, or biperiodic); NaN for an empty
// cell, a failed REQUIRE when there is no such row.
double tableValue(const study::CsvTable& t, const std::string& key, double width, bool biperiodic,
                  const std::string& column) {
  const auto at = [&](const std::string& name) {
    const auto it = std::find(t.columns.begin(), t.columns.end(), name);
    REQUIRE(it != t.columns.end());
    return static_cast<std::size_t>(it - t.columns.begin());
  };
  const std::size_t keyAt = at("key"), wAt = at("W"), periodicAt = at("biperiodic"), valueAt = at(column);
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    if (t.text[i][keyAt] == key && t.rows[i][wAt] == width && (t.rows[i][periodicAt] == 1.0) == biperiodic)
      return t.rows[i][valueAt];
  FAIL("no row " << key << " W=" << width);
  return 0.0;
}

// The keys of a table file, once each.
std::set<std::string> tableKeys(const study::CsvTable& t) {
  std::set<std::string> keys;
  for (const auto& row : t.text) keys.insert(row[0]);
  return keys;
}

// The Markdown run table's links: the rows from "| run |" to the end of the table, as (name, target).
std::vector<std::pair<std::string, std::string>> runLinks(const std::string& md) {
  std::vector<std::pair<std::string, std::string>> links;
  const std::size_t head = md.find("| run | configuration |");
  if (head == std::string::npos) return links;
  std::istringstream in(md.substr(head));
  std::string line;
  std::getline(in, line);  // head
  std::getline(in, line);  // |---|
  while (std::getline(in, line) && line.rfind("| [", 0) == 0) {
    const std::size_t close = line.find("](");
    links.emplace_back(line.substr(3, close - 3), line.substr(close + 2, line.find(')', close) - close - 2));
  }
  return links;
}

}  // namespace

TEST_CASE("replica statistics and backend differences") {
  const study::ReplicaStat s = study::replicaStat({1.0, 2.0, 3.0});
  CHECK(s.n == 3);
  CHECK(s.mean == Approx(2.0));
  CHECK(s.std == Approx(1.0));  // sample std, n - 1 in the denominator
  const study::ReplicaStat one = study::replicaStat({0.5});
  CHECK(one.n == 1);
  CHECK(one.std == 0.0);
  const study::ReplicaStat b = study::replicaStat({-1.0, 1.0, 3.0, 1.0});  // mean 1, var 8/3
  const study::BackendDifference d = study::backendDifference(s, b);
  CHECK(d.value == Approx(1.0));
  REQUIRE(d.uncertainty);
  CHECK(*d.uncertainty == Approx(std::sqrt(1.0 / 3.0 + (8.0 / 3.0) / 4.0)));
  CHECK_FALSE(study::backendDifference(s, one).uncertainty);
}

TEST_CASE("flattened result: numbers and booleans kept, nulls kept as not applicable, config skipped") {
  const json r = {{"solid_fraction", 0.6},
                  {"equilibrium", {{"reached", false}}},
                  {"nematic", {{"bulk", nullptr}}},
                  {"backend", "nscd"},
                  {"config", {{"box", {{"width", 5}}}}}};
  const auto v = study::flattenResult(r);
  CHECK(v.at("solid_fraction") == Approx(0.6));
  CHECK(*v.at("equilibrium/reached") == 0.0);
  CHECK_FALSE(v.at("nematic/bulk").has_value());
  CHECK(v.count("config/box/width") == 0);
  CHECK(v.count("backend") == 0);
}

TEST_CASE("flattened result: a hand-edited result.json nested 200,000 objects deep is read, its depths skipped") {
  // Once a stack overflow (SIGSEGV) of `confpack report`.
  std::string text = R"({"solid_fraction": 0.6, "deep": )";
  for (int k = 0; k < 200000; ++k) text += R"({"a": )";
  text += "1";
  text += std::string(200000, '}') + "}";
  const auto v = study::flattenResult(json::parse(text));
  CHECK(v.at("solid_fraction") == Approx(0.6));
  CHECK(v.size() == 1);
}

TEST_CASE("report of a synthetic study: fits recover phi_bulk and C, tables side by side") {
  const fs::path dir = makeStudy("complete", false);
  const study::ReportSummary s = study::writeReport(dir, dir / "report");
  CHECK(s.runs == 30);
  CHECK(s.done == 30);
  CHECK(s.failed == 0);
  CHECK(s.missing == 0);
  const std::string md = slurp(s.markdown);
  const std::string html = slurp(s.html);
  // Fit rows: phi_bulk and C of each backend, exactly on the synthetic law.
  CHECK(md.find("| MSP x_S=0 mu_w=0 | nscd | 4 | 0.6400 ± ") != std::string::npos);
  CHECK(md.find("| 0.500 ± ") != std::string::npos);
  CHECK(md.find("| MSP x_S=0 mu_w=0 | bullet | 4 | 0.6300 ± ") != std::string::npos);
  CHECK(md.find("| 0.400 ± ") != std::string::npos);
  // Z(W) fit: Z_bulk = 6, C_Z = 1.2, zeta_Z = 0.2.
  CHECK(md.find("| 6.0000 ± ") != std::string::npos);
  CHECK(md.find("| 1.200 ± ") != std::string::npos);
  CHECK(md.find("| 0.200 |") != std::string::npos);
  // Backend difference of the fitted parameters: 0.01 and 0.1.
  CHECK(md.find("| +0.0100 ± ") != std::string::npos);
  CHECK(md.find("| +0.100 ± ") != std::string::npos);
  // Per-configuration values, in tables/: mean +- std over 3 replicas; W = 10 nscd phi = 0.64 - 0.05 = 0.59.
  const fs::path report = dir / "report";
  const study::CsvTable phi = readTable(report, "solid_fraction.csv");
  CHECK(tableValue(phi, "solid_fraction", 10, false, "nscd_mean") == Approx(0.59));
  CHECK(tableValue(phi, "solid_fraction", 10, false, "nscd_std") == Approx(kDelta));
  CHECK(tableValue(phi, "solid_fraction", 10, false, "nscd_n") == 3);
  CHECK(tableValue(phi, "solid_fraction", 12, true, "bullet_mean") == Approx(0.63));
  // Difference at W = 5: (0.64 - 0.1) - (0.63 - 0.08) = -0.01, uncertainty sqrt(2 delta^2 / 3).
  CHECK(tableValue(phi, "solid_fraction", 5, false, "nscd_minus_bullet") == Approx(-0.01));
  CHECK(tableValue(phi, "solid_fraction", 5, false, "nscd_minus_bullet_uncertainty") ==
        Approx(std::sqrt(2.0 * kDelta * kDelta / 3.0)));
  // Every quantity present in result.json is in the table of its group, none on the page as a heading.
  const std::vector<std::pair<std::string, std::vector<std::string>>> groups = {
      {"solid_fraction.csv", {"solid_fraction"}},
      {"coordination.csv", {"coordination/Z", "coordination/rattler_fraction"}},
      {"interpenetration.csv", {"interpenetration_percent/exact"}},
      {"order.csv", {"anisotropy"}},
      {"equilibrium.csv", {"equilibrium/max_force_ratio", "equilibrium/reached"}},
      {"profile_fit.csv", {"profile_fit/lambda_L", "profile_fit/phi_bulk"}},
      {"cost.csv", {"timing/wall_s", "timing/steps"}},
      {"other.csv", {"n_grains"}}};
  for (const auto& [file, keys] : groups) {
    INFO(file);
    const std::set<std::string> inFile = tableKeys(readTable(report, file));
    for (const std::string& k : keys) CHECK(inFile.count(k) == 1);
    CHECK(md.find("[tables/" + file + "](tables/" + file + ")") != std::string::npos);
    CHECK(html.find("<a href=\"tables/" + file + "\">") != std::string::npos);
  }
  for (const auto& [key, _] : study::flattenResult(json::parse(slurp(dir / "runs" / "r0001" / "result.json")))) {
    INFO(key);
    CHECK(md.find("# " + key + "\n") == std::string::npos);
    CHECK(html.find(">" + key + "</h") == std::string::npos);
  }
  CHECK(md.find("\n### ") == std::string::npos);
  // Nulls in every run are named as not applicable, and have no rows.
  CHECK(md.find("Not applicable to any run of this study (null in every result.json): ") != std::string::npos);
  CHECK(md.find("nematic/bulk") != std::string::npos);
  CHECK(tableKeys(readTable(report, "order.csv")).count("nematic/bulk") == 0);
  CHECK(md.find("Every run finished") != std::string::npos);
  // Figures with their data next to them; the HTML inlines the SVG.
  CHECK(fs::exists(dir / "report" / "figures" / "phi_vs_invW.csv"));
  CHECK(fs::exists(dir / "report" / "figures" / "phi_vs_invW.gp"));
  if (s.gnuplotUsed) {
    CHECK(fs::exists(dir / "report" / "figures" / "phi_vs_invW.svg"));
    CHECK(html.find("<svg") != std::string::npos);
    CHECK(md.find("![") != std::string::npos);
  }
  CHECK(md.find("## Solid-fraction profiles phi(y)") != std::string::npos);
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}

TEST_CASE("report shows failed and missing runs as such") {
  const fs::path dir = makeStudy("failures", true);
  const study::ReportSummary s = study::writeReport(dir, dir / "report");
  CHECK(s.failed == 3);
  CHECK(s.missing == 1);
  CHECK(s.done == 26);
  const std::string md = slurp(s.markdown);
  CHECK(md.find("solver diverged") != std::string::npos);
  CHECK(md.find("| [r0000](../runs/r0000) |") != std::string::npos);
  CHECK(md.find("missing: not run or interrupted") != std::string::npos);
  // Each unequilibrated run says what stopped it.
  CHECK(md.find("nscd | done, NOT equilibrated | 0.5920 | 1.5 | finisher not at rest after 3000 steps |") !=
        std::string::npos);
  CHECK(md.find("bullet | done, NOT equilibrated | 0.5920 | 1.5 | stopped at the time limit |") != std::string::npos);
  // The problem runs lead the run table: r0000 (interrupted), 3 failed, 2 not at rest, then the 24 others.
  const auto links = runLinks(md);
  REQUIRE(links.size() == 30);
  const std::string table = md.substr(md.find("| run | configuration |"));
  for (std::size_t i = 0; i < links.size(); ++i) {
    INFO(links[i].first);
    const std::size_t row = table.find("| [" + links[i].first + "](");
    const std::string line = table.substr(row, table.find('\n', row) - row);
    const bool problem = line.find("| done |") == std::string::npos;
    CHECK(problem == (i < 6));
  }
  CHECK(links.front().first == "r0000");
  // bullet at W = 20 has no replica: no mean, n = 0.
  const study::CsvTable phi = readTable(dir / "report", "solid_fraction.csv");
  CHECK(tableValue(phi, "solid_fraction", 20, false, "nscd_mean") == Approx(0.615));
  CHECK(tableValue(phi, "solid_fraction", 20, false, "nscd_n") == 3);
  CHECK(std::isnan(tableValue(phi, "solid_fraction", 20, false, "bullet_mean")));
  CHECK(tableValue(phi, "solid_fraction", 20, false, "bullet_n") == 0);
  CHECK(std::isnan(tableValue(phi, "solid_fraction", 20, false, "nscd_minus_bullet")));
  // nscd at W = 4 lost seed 1 (r0000): n = 2 there, mean of seeds 2 and 3.
  CHECK(tableValue(phi, "solid_fraction", 4, false, "nscd_n") == 2);
  CHECK(tableValue(phi, "solid_fraction", 4, false, "nscd_mean") == Approx(0.516));
  CHECK(tableValue(phi, "solid_fraction", 4, false, "nscd_std") == Approx(kDelta / std::sqrt(2.0)));
  // The fits still run on the widths that have data (bullet: 3 widths).
  CHECK(md.find("| MSP x_S=0 mu_w=0 | bullet | 3 | 0.6300 ± ") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("the report names the build that wrote it and counts the runs each build computed") {
  const fs::path dir = makeStudy("builds", false);
  // Ten runs per build: two revisions, and results that recorded no version (the synthetic ones).
  for (int i = 0; i < 20; ++i) {
    const fs::path file = dir / "runs" / fmt::format("r{:04d}", i) / "result.json";
    json r = json::parse(slurp(file));
    r["confpack_version"] = "0.1.0";
    r["confpack_revision"] = i < 10 ? "0123456789ab" : "ba9876543210-dirty";
    std::ofstream(file) << r.dump();
  }
  study::ReportOptions o;
  o.gnuplot.clear();  // figures are not the point here
  const study::ReportSummary s = study::writeReport(dir, dir / "report", o);
  const std::string md = slurp(s.markdown);
  CHECK(md.find(fmt::format("by confpack {} (revision {})", core::version(), core::sourceRevision())) !=
        std::string::npos);
  CHECK(md.find("The finished runs were computed by confpack 0.1.0 at revision 0123456789ab (10 runs); confpack "
                "0.1.0 at revision ba9876543210-dirty (10 runs); a build that recorded no version (10 runs).") !=
        std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("the report says what boxes the runs had, and a grain cap's shorter boxes stay in their family") {
  const fs::path plain = makeStudy("boxes", false);
  study::ReportOptions o;
  o.gnuplot.clear();
  std::string md = slurp(study::writeReport(plain, plain / "report", o).markdown);
  CHECK(md.find("Boxes L_x x W x h with h = 4 d_L (the target height) and L_x = 6 d_L.") != std::string::npos);
  fs::remove_all(plain);

  // At phi 0.6, 6 x W x 4 holds about 110 spheres at W = 4, 137 at W = 5, 275 at W = 10, 550 at
  // W = 20 and 330 biperiodic (12): capped at 200, the last three are shortened to 6 * 200 / n
  // (n a third of a percent less: the size spread), rounded down to the hundredth.
  const fs::path capped = makeStudy("capped", false, false, 200);
  md = slurp(study::writeReport(capped, capped / "report", o).markdown);
  CHECK(md.find("but where a box would hold more than 200 grains (deposition.grain_cap), shortened along x to hold "
                "about that many: MSP xS=0 W=10 L_x = 4.36; MSP xS=0 W=20 L_x = 2.18; MSP xS=0 W=bi12 L_x = 3.63.") !=
        std::string::npos);
  // One family over the four widths, as without the cap: the fitted L_x is not a setting that splits it.
  CHECK(md.find("Beyond W, shape, x_S, mu_w, seed and backend this study varies") == std::string::npos);
  CHECK(md.find("| MSP x_S=0 mu_w=0 | nscd | 4 |") != std::string::npos);
  fs::remove_all(capped);
}

TEST_CASE("report without gnuplot keeps the data and says so") {
  const fs::path dir = makeStudy("nognuplot", false);
  study::ReportOptions o;
  o.gnuplot = "/nonexistent/gnuplot";
  const study::ReportSummary s = study::writeReport(dir, dir / "report", o);
  CHECK_FALSE(s.gnuplotUsed);
  const std::string md = slurp(s.markdown);
  CHECK(md.find("was not found") != std::string::npos);
  CHECK(fs::exists(dir / "report" / "figures" / "phi_vs_invW.csv"));
  CHECK_FALSE(fs::exists(dir / "report" / "figures" / "phi_vs_invW.svg"));
  fs::remove_all(dir);
}

TEST_CASE("report with a gnuplot that fails its --version check says how, not that it was not found") {
  // The failure this guards against: a --gnuplot script that exits 3 was reported as "not found".
  const fs::path dir = makeStudy("brokengnuplot", false);
  const fs::path gnuplot = dir / "broken-gnuplot";
  std::ofstream(gnuplot) << "#!/bin/sh\nexit 3\n";
  fs::permissions(gnuplot, fs::perms::owner_all);
  study::ReportOptions o;
  o.gnuplot = gnuplot;
  const study::ReportSummary s = study::writeReport(dir, dir / "report", o);
  CHECK_FALSE(s.gnuplotUsed);
  const std::string problem = "failed its check (`" + gnuplot.string() + " --version` exited with status 3)";
  CHECK(s.gnuplotProblem == problem);
  const std::string md = slurp(s.markdown);
  CHECK(md.find("gnuplot ('" + gnuplot.string() + "') " + problem + ": figures are not drawn") != std::string::npos);
  CHECK(md.find("was not found") == std::string::npos);
  // A gnuplot that is not there still reads as not found.
  o.gnuplot = dir / "absent-gnuplot";
  CHECK_THAT(study::writeReport(dir, dir / "report2", o).gnuplotProblem, Catch::StartsWith("was not found ("));
  fs::remove_all(dir);
}

TEST_CASE("report with a gnuplot that fails: each figure says so by name, the rest of the report is written") {
  const fs::path dir = makeStudy("badgnuplot", false);
  const fs::path gnuplot = dir / "failing gnuplot";
  std::ofstream(gnuplot) << "#!/bin/sh\n[ \"$1\" = --version ] && exit 0\necho \"cannot draw $1\" >&2\nexit 2\n";
  fs::permissions(gnuplot, fs::perms::owner_all);
  study::ReportOptions o;
  o.gnuplot = gnuplot;
  const study::ReportSummary s = study::writeReport(dir, dir / "report", o);
  CHECK(s.gnuplotUsed);
  CHECK(s.figures > 0);
  CHECK(s.figureErrors.size() == s.figures);
  CHECK_THAT(s.figureErrors.front(),
             Catch::StartsWith("figure phi_vs_invW: gnuplot failed: exited with status 2: cannot draw phi_vs_invW.gp"));
  const std::string md = slurp(s.markdown);
  const std::string html = slurp(s.html);
  CHECK(md.find("*Figure phi_vs_invW: phi against d_L/W with the fits phi_bulk - C/W (biperiodic at 0)* (not drawn: "
                "gnuplot failed: exited with status 2: cannot draw phi_vs_invW.gp (its output: "
                "figures/phi_vs_invW.log); data in") != std::string::npos);
  CHECK(html.find("(not drawn: gnuplot failed: exited with status 2") != std::string::npos);
  CHECK(html.find("<svg") == std::string::npos);
  CHECK(md.find("| MSP x_S=0 mu_w=0 | nscd | 4 | 0.6400 ± ") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "report" / "figures" / "phi_vs_invW.svg"));
  CHECK(fs::exists(dir / "report" / "figures" / "phi_vs_invW.log"));
  fs::remove_all(dir);
}

namespace {

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

// The verdict section of a report: from its heading to the next section's.
std::string verdictOf(const std::string& md) {
  const std::size_t at = md.find("## Cross-solver verdict");
  return at == std::string::npos ? std::string() : md.substr(at, md.find("\n## ", at) - at);
}

}  // namespace

TEST_CASE("summary leads the report with the fit section's phi_bulk, C, Z_bulk and C_Z") {
  const fs::path dir = makeStudy("summary", false);
  const study::ReportSummary s = study::writeReport(dir, dir / "report");
  const std::string md = slurp(s.markdown);
  const std::string html = slurp(s.html);
  // Summary, then verdict, then the figures (phi first), then the run table, then the cost, in both renderings.
  const std::size_t summaryAt = md.find("## Summary"), verdictAt = md.find("## Cross-solver verdict"),
                    phiAt = md.find("## Solid fraction phi against d_L/W"), runsAt = md.find("## Runs"),
                    costAt = md.find("## Cost");
  REQUIRE(summaryAt != std::string::npos);
  CHECK(summaryAt < verdictAt);
  CHECK(verdictAt < phiAt);
  CHECK(phiAt < md.find("](figures/phi_vs_invW.", phiAt));
  CHECK(md.find("](figures/phi_vs_invW.", phiAt) < md.find("## Coordination number Z against d_L/W"));
  CHECK(md.find("## Coordination number Z against d_L/W") < md.find("## Wall ordering length lambda_L"));
  CHECK(md.find("## Wall ordering length lambda_L") < md.find("## Solid-fraction profiles phi(y)"));
  CHECK(md.find("## Solid-fraction profiles phi(y)") < runsAt);
  CHECK(runsAt < costAt);
  CHECK(costAt != std::string::npos);
  const std::vector<std::string> htmlOrder = {"<h2>Summary", "<h2>Cross-solver verdict</h2>",
                                              "<h2>Solid fraction phi against d_L/W</h2>", "<h2>Runs</h2>",
                                              "<h2>Cost</h2>"};
  for (std::size_t i = 0; i + 1 < htmlOrder.size(); ++i) {
    INFO(htmlOrder[i]);
    REQUIRE(html.find(htmlOrder[i]) != std::string::npos);
    CHECK(html.find(htmlOrder[i]) < html.find(htmlOrder[i + 1]));
  }
  // Each section of a figure is named after its quantity and defines it, with no section number.
  CHECK(md.find("## Solid fraction phi against d_L/W\n\nThe solid fraction phi is ") != std::string::npos);
  CHECK(md.find("## Coordination number Z against d_L/W\n\nThe coordination number Z is ") != std::string::npos);
  CHECK(md.find("SPEC") == std::string::npos);
  struct Expected {
    std::string backend, phiBulk, c;
  };
  for (const Expected& e : {Expected{"nscd", "0.6400", "0.500"}, Expected{"bullet", "0.6300", "0.400"}}) {
    const std::string& backend = e.backend;
    INFO(backend);
    // The fit section's rows (phi first, Z second), on the synthetic law.
    const std::string fitPrefix = "| MSP x_S=0 mu_w=0 | " + backend + " | 4 | ";
    const auto phiFit = rowCells(md, fitPrefix, phiAt);
    const auto zFit = rowCells(md, fitPrefix, md.find(fitPrefix, phiAt) + 1);
    REQUIRE(phiFit.size() > 5);
    REQUIRE(zFit.size() > 5);
    CHECK_THAT(phiFit[3], Catch::StartsWith(e.phiBulk + " ± "));
    CHECK_THAT(phiFit[4], Catch::StartsWith(e.c + " ± "));
    CHECK_THAT(zFit[3], Catch::StartsWith("6.0000 ± "));
    CHECK_THAT(zFit[4], Catch::StartsWith("1.200 ± "));
    // The summary row: every run at equilibrium, the same numbers as the fits, the fit quality.
    const auto row = rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | " + backend + " |", summaryAt);
    REQUIRE(row.size() == 12);
    CHECK(md.find("| MSP: spheres x_S = 0, mu_w = 0 | " + backend + " |", summaryAt) < verdictAt);
    CHECK(row[2] == "15 / 15");
    CHECK(row[3] == "-");  // these synthetic runs report no bulk region
    CHECK(row[4] == "4 to 20");
    CHECK(row[5] == phiFit[3]);
    CHECK(row[6] == phiFit[4]);
    CHECK(row[7] == "chi²/dof " + phiFit[7] + ", Q " + phiFit[8]);
    CHECK(row[8] == zFit[3]);
    CHECK(row[9] == zFit[4]);
    // lambda_L/d_avg of the profile averaged over the replicas at W = 10, the runs' law.
    CHECK_THAT(row[10], Catch::StartsWith(backend == "nscd" ? "1.25 ± " : "1.5 ± "));
    CHECK_THAT(row[10], Catch::EndsWith("(W = 10)"));
    CHECK_THAT(row[11], Catch::StartsWith(backend == "nscd" ? "0.01 ± " : "0.2 ± "));
  }
  // Without --reference there is no reference column.
  CHECK(md.find("reference |") == std::string::npos);
  // Quantities are named and defined, never numbered.
  CHECK(md.find("- phi_bulk: solid fraction far from the walls") != std::string::npos);
  CHECK(md.find("- lambda_L/d_avg: length over which the wall's layering") != std::string::npos);
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}

TEST_CASE("cross-solver verdict: agree on a shared law, differ on a shifted phi_bulk") {
  SECTION("the backends share the law") {
    const fs::path dir = makeStudy("agree", false, true);
    const std::string verdict = verdictOf(slurp(study::writeReport(dir, dir / "report").markdown));
    CHECK_THAT(verdict, Catch::Contains("For MSP: spheres x_S = 0, mu_w = 0: nscd and bullet agree on phi_bulk "
                                        "within 2 standard errors (0.6400 ± "));
    CHECK_THAT(verdict, Catch::Contains("nscd and bullet agree on C within 2 standard errors (0.500 ± "));
    CHECK_THAT(verdict, Catch::Contains("| MSP: spheres x_S = 0, mu_w = 0 | phi_bulk | "));
    CHECK_THAT(verdict, !Catch::Contains("differ on"));
    CHECK_THAT(verdict, !Catch::Contains("(*)"));
    // Identical values without a standard error (the interpenetration here) are the same, not undecided.
    CHECK_THAT(verdict, Catch::Contains("nscd and bullet give the same interpenetration (0.01 ± 0 against 0.01 ± 0)."));
    CHECK_THAT(verdict, !Catch::Contains("equilibrium"));
    fs::remove_all(dir);
  }
  SECTION("bullet's phi_bulk is 0.01 lower, many standard errors") {
    const fs::path dir = makeStudy("differ", false);
    const std::string verdict = verdictOf(slurp(study::writeReport(dir, dir / "report").markdown));
    CHECK_THAT(verdict, Catch::Contains("nscd and bullet differ on phi_bulk by +0.01 ± 0.0018, 5.7 standard errors "
                                        "(0.6400 ± 0.0012 against 0.6300 ± 0.0012)."));
    const auto row = rowCells(verdict, "| MSP: spheres x_S = 0, mu_w = 0 | phi_bulk |");
    REQUIRE(row.size() == 7);
    CHECK(row[4] == "+0.01");
    CHECK(row[6] == "yes: differ (*)");
    // Z follows one law in both backends: they agree on it.
    CHECK_THAT(verdict, Catch::Contains("nscd and bullet agree on Z_bulk within 2 standard errors (6.0000 ± "));
    fs::remove_all(dir);
  }
}

TEST_CASE("cross-solver verdict with Bullet's piles settled: a difference that vanishes at rest is 'not at rest'") {
  const fs::path dir = makeStudy("settled", false, false, 0, true);
  const std::string md = slurp(study::writeReport(dir, dir / "report").markdown);
  const std::string verdict = verdictOf(md);
  // The settled piles are a third series, beside the two backends' own.
  CHECK_THAT(md, Catch::Contains("bullet_settled"));
  const auto row = rowCells(verdict, "| MSP: spheres x_S = 0, mu_w = 0 | phi_bulk |");
  REQUIRE(row.size() == 12);
  CHECK(row[6] == "yes: differ (*)");        // nscd against bullet as it stopped: 0.01 apart
  CHECK(row[7].rfind("0.6400 ± ", 0) == 0);  // bullet settled: nscd's law
  CHECK(row[10] == "no: agree");
  CHECK(row[11] == "not at rest");
  CHECK_THAT(verdict, Catch::Contains("On phi_bulk: not at rest."));
  // A quantity on which the backends agree as they stopped and once settled has nothing to explain.
  const auto z = rowCells(verdict, "| MSP: spheres x_S = 0, mu_w = 0 | Z_bulk |");
  REQUIRE(z.size() == 12);
  CHECK(z[11] == "none");
  // The settles are second results of the table's runs, not runs of their own.
  CHECK_THAT(md, Catch::Contains("30 runs: 30 done"));
  fs::remove_all(dir);
}

TEST_CASE("the summary opens with a warning where a family's boxes are too small or its fits too narrow") {
  SECTION("a quick-scale study: a bulk 1 d_L thick of 40 grains, widths 3 to 6") {
    gSizes = {1.2, 40.0, json::array({3, 4.5, 6, "biperiodic"})};
    const fs::path dir = makeStudy("adequacy_small", false);
    gSizes = {};
    const std::string md = slurp(study::writeReport(dir, dir / "report").markdown);
    const std::string summary =
        md.substr(md.find("## Summary"), md.find("## Cross-solver verdict") - md.find("## Summary"));
    CHECK_THAT(summary, Catch::Contains("Warning: these numbers cannot carry their physics."));
    CHECK_THAT(summary, Catch::Contains("its bulk region is 1.2 d_L thick (fewer than 4)"));
    CHECK_THAT(summary, Catch::Contains("it holds 40 grains (fewer than 300)"));
    CHECK_THAT(summary, Catch::Contains("its fits span W = 3 to 6, a factor 2 (less than 3)"));
    // The sizes behind it, in the table.
    const auto row = rowCells(summary, "| MSP: spheres x_S = 0, mu_w = 0 | nscd |");
    REQUIRE(row.size() > 4);
    CHECK(row[3] == "1.2 / 40");
    CHECK(row[4] == "3 to 6");
    fs::remove_all(dir);
  }
  SECTION("a medium-scale study: a bulk 6 d_L thick of 410 grains, widths 4 to 20: no warning") {
    gSizes = {6.0, 410.0, json::array({4, 5, 10, 20, "biperiodic"})};
    const fs::path dir = makeStudy("adequacy_medium", false);
    gSizes = {};
    const std::string md = slurp(study::writeReport(dir, dir / "report").markdown);
    CHECK_THAT(md, !Catch::Contains("Warning: these numbers"));
    CHECK(rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | nscd |")[3] == "6.0 / 410");
    fs::remove_all(dir);
  }
}

TEST_CASE("the verdict says whose contact networks carry self-stresses, where, and how many motions are free") {
  const fs::path dir = makeStudy("rigidity", false);
  study::ReportOptions o;
  o.gnuplot.clear();
  const std::string md = slurp(study::writeReport(dir, dir / "report", o).markdown);
  CHECK(md.find("nscd's 15 packings: no self-stress (the geometry fixes the contact forces), 1 % of their "
                "motions free (mechanisms, mean).") != std::string::npos);
  CHECK(md.find("bullet's 15 packings: 15 with self-stresses, 0.1 per constraint (mean), 15 with some between "
                "grains; 10 % of their motions free (mechanisms, mean).") != std::string::npos);
  // Each run's numbers are in the coordination table.
  CHECK(tableKeys(readTable(dir / "report", "coordination.csv")).count("rigidity/self_stresses") == 1);
  fs::remove_all(dir);
}

TEST_CASE("a number without a standard error is shown as such and the verdict does not judge it") {
  // Bullet keeps W = 10 (3 runs) and one run at W = 20: its phi(W) is an unweighted line through two
  // widths, and lambda_L/d_avg of its widest sample comes from one run. nscd keeps everything.
  // keep(width, seed) says which of bullet's confined runs stay done.
  const auto reportWithout = [](const std::string& name, const auto& keep) {
    const fs::path dir = makeStudy(name, false);
    for (const auto& entry : fs::directory_iterator(dir / "runs")) {
      const json cfg = json::parse(slurp(entry.path() / "config.json"));
      if (cfg["backend"] == "bullet" && !cfg["box"]["periodic_y"].get<bool>() &&
          !keep(cfg["box"]["width"].get<double>(), cfg["seed"].get<int>()))
        fs::remove(entry.path() / study::kDoneMarker);
    }
    const std::string md = slurp(study::writeReport(dir, dir / "report").markdown);
    fs::remove_all(dir);
    return md;
  };
  // With every width but W = 20 at 3 runs, the fit is unweighted over 4 widths: no chi², its residuals.
  const std::string unweighted = reportWithout("unweighted", [](double w, int seed) { return w != 20.0 || seed == 1; });
  CHECK_THAT(rowCells(unweighted, "| MSP: spheres x_S = 0, mu_w = 0 | bullet |", unweighted.find("## Summary")).at(7),
             Catch::StartsWith("unweighted (a width without a standard error): residual sum of squares "));
  const std::string md =
      reportWithout("no_error", [](double w, int seed) { return w == 10.0 || (w == 20.0 && seed == 1); });
  const auto bullet = rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | bullet |", md.find("## Summary"));
  REQUIRE(bullet.size() == 12);
  // The line through phi(10) = 0.63 - 0.4/10 (a mean on bullet's law) and phi(20) = 0.63 - 0.4/20 - 0.002
  // (seed 1's offset): C = 0.018 / 0.05 = 0.36, phi_bulk = 0.59 + 0.036.
  CHECK(bullet[5] == "0.6260 (no SE)");
  CHECK(bullet[6] == "0.360 (no SE)");
  CHECK(bullet[7] == "exact through 2 widths: no standard errors");
  // lambda_L/d_avg is read at W = 10, where bullet kept its 3 runs: it has an error, and the
  // verdict judges it (1.25 against 1.5, the runs' laws).
  CHECK_THAT(bullet[10], Catch::StartsWith("1.5 ± "));
  const std::string verdict = verdictOf(md);
  const auto lambda = rowCells(verdict, "| MSP: spheres x_S = 0, mu_w = 0 | lambda_L/d_avg |");
  REQUIRE(lambda.size() == 7);
  CHECK(lambda[6] == "yes: differ (*)");
  CHECK(rowCells(verdict, "| MSP: spheres x_S = 0, mu_w = 0 | phi_bulk |").at(6) == "no standard error");
  // The fit section's backend differences say the same of the fitted parameters.
  const std::size_t differencesAt = md.find("Backend differences of the fitted parameters");
  REQUIRE(differencesAt != std::string::npos);
  const auto difference = rowCells(md, "| MSP x_S=0 mu_w=0 |", differencesAt);
  REQUIRE(difference.size() == 3);
  CHECK(difference[1] == "+0.0140 (no SE)");  // 0.64 - 0.626
  CHECK(difference[2] == "+0.140 (no SE)");   // 0.5 - 0.36
}

TEST_CASE("summary and verdict say which runs were not at equilibrium, failed or are missing") {
  const fs::path dir = makeStudy("verdict_failures", true);
  const std::string md = slurp(study::writeReport(dir, dir / "report").markdown);
  // nscd: r0000 interrupted, seed 3 at W = 10 not at rest; bullet: W = 20 failed, seed 3 at W = 10 not at rest.
  CHECK(rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | nscd |").at(2) == "13 / 15");
  CHECK(rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | bullet |").at(2) == "11 / 15");
  const std::string verdict = verdictOf(md);
  CHECK_THAT(verdict, Catch::Contains("1 of nscd's 14 finished runs did not reach equilibrium: the comparison is "
                                      "partly of unequilibrated piles."));
  CHECK_THAT(verdict, Catch::Contains("1 of bullet's 12 finished runs did not reach equilibrium"));
  CHECK_THAT(verdict, Catch::Contains("3 of bullet's 15 runs failed."));
  CHECK_THAT(verdict, Catch::Contains("1 of nscd's 15 runs is missing (not run or interrupted)."));
  // A bullet run interrupted too (r0001: W = 4, seed 1): failed and missing runs are counted apart.
  fs::remove(dir / "runs" / "r0001" / study::kDoneMarker);
  const std::string again = verdictOf(slurp(study::writeReport(dir, dir / "report").markdown));
  CHECK_THAT(again, Catch::Contains("4 of bullet's 15 runs did not finish: 3 failed, 1 is missing (not run or "
                                    "interrupted)."));
  fs::remove_all(dir);
}

TEST_CASE("the run table appears once, each run name a link to its folder relative to the report") {
  const fs::path dir = makeStudy("runlinks", true);
  for (const fs::path& out : {dir / "report", dir / "elsewhere" / "deeper"}) {
    INFO(out);
    const std::string md = slurp(study::writeReport(dir, out).markdown);
    const std::string html = slurp(out / "report.html");
    CHECK(md.find("| run | configuration |") == md.rfind("| run | configuration |"));
    CHECK(md.find("## Runs") == md.rfind("## Runs"));
    const auto links = runLinks(md);
    REQUIRE(links.size() == 30);
    std::set<std::string> names;
    for (const auto& [name, target] : links) {
      INFO(name << " -> " << target);
      names.insert(name);
      CHECK(fs::path(target).is_relative());
      CHECK(fs::is_directory(out / target));
      CHECK(fs::equivalent(out / target, dir / "runs" / name));
      // Listed once: in the run table and nowhere else as a link.
      CHECK(md.find("[" + name + "](") == md.rfind("[" + name + "]("));
      CHECK(html.find("<a href=\"" + target + "\">" + name + "</a>") != std::string::npos);
    }
    CHECK(names.size() == 30);
  }
  fs::remove_all(dir);
}

TEST_CASE("a report without run links names every run and the sweep folder, and points into neither") {
  const fs::path dir = makeStudy("nolinks", true);
  const fs::path out = dir.parent_path() / (dir.filename().string() + "_published");
  study::ReportOptions options;
  options.gnuplot.clear();
  options.runLinks = false;
  const std::string md = slurp(study::writeReport(dir, out, options).markdown);
  const std::string html = slurp(out / "report.html");
  CHECK(runLinks(md).empty());
  const std::string table = md.substr(md.find("| run | configuration |"));
  for (int i = 0; i < 30; ++i) {
    const std::string name = fmt::format("r{:04d}", i);
    INFO(name);
    CHECK(table.find("| " + name + " |") != std::string::npos);
    CHECK(md.find("runs/" + name) == std::string::npos);
    CHECK(html.find("runs/" + name) == std::string::npos);
  }
  // The sweep folder by its name, not by a path of the machine that wrote the report.
  CHECK(md.find(dir.parent_path().string()) == std::string::npos);
  CHECK(html.find(dir.parent_path().string()) == std::string::npos);
  CHECK(md.find("Sweep folder: " + dir.filename().string() + " (its run folders are not part of this report)") !=
        std::string::npos);
  CHECK(md.find("The run folders are not part of this report.") != std::string::npos);
  fs::remove_all(out);
  fs::remove_all(dir);
}

TEST_CASE("tables/*.csv read back give the mean and n of the runs' result.json") {
  const fs::path dir = makeStudy("tables", true);
  const fs::path report = dir / "report";
  study::writeReport(dir, report);
  // The values of the finished runs, from their own folders: (key, backend, W, biperiodic) -> values.
  std::map<std::tuple<std::string, std::string, double, bool>, std::vector<double>> values;
  for (const auto& e : fs::directory_iterator(dir / "runs")) {
    if (!fs::exists(e.path() / study::kDoneMarker)) continue;
    const json cfg = json::parse(slurp(e.path() / "config.json"));
    const json result = json::parse(slurp(e.path() / "result.json"));
    const double w = cfg["box"]["width"].get<double>();
    const bool periodic = cfg["box"]["periodic_y"].get<bool>();
    const std::string backend = cfg["backend"].get<std::string>();
    values[{"solid_fraction", backend, w, periodic}].push_back(result["solid_fraction"].get<double>());
    values[{"coordination/Z", backend, w, periodic}].push_back(result["coordination"]["Z"].get<double>());
    values[{"timing/wall_s", backend, w, periodic}].push_back(result["timing"]["wall_s"].get<double>());
  }
  REQUIRE(values.size() == 3 * 2 * 5 - 3);  // bullet at W = 20 failed for every seed
  const std::map<std::string, std::string> fileOf = {
      {"solid_fraction", "solid_fraction.csv"}, {"coordination/Z", "coordination.csv"}, {"timing/wall_s", "cost.csv"}};
  for (const auto& [where, v] : values) {
    const auto& [key, backend, w, periodic] = where;
    INFO(key << " " << backend << " W=" << w << (periodic ? " biperiodic" : ""));
    double mean = 0.0;
    for (double x : v) mean += x;
    mean /= static_cast<double>(v.size());
    const study::CsvTable t = readTable(report, fileOf.at(key));
    CHECK(tableValue(t, key, w, periodic, backend + "_n") == static_cast<double>(v.size()));
    CHECK(tableValue(t, key, w, periodic, backend + "_mean") == Approx(mean).epsilon(1e-14));
  }
  fs::remove_all(dir);
}

TEST_CASE("a family's per-sample quantities are read at one configuration for every backend, the one most have") {
  // Pinacoids at W = 10 and biperiodic, Bullet's piles settled at W = 10 only: the simple contacts
  // are 5 a grain at W = 10 and 5.5 in the biperiodic box. The settled series has no biperiodic
  // value, so all three are read at W = 10, not nscd's and Bullet's in the biperiodic box.
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_report_sample_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const study::SweepSpec spec = study::parseSweepSpec(json::parse(R"({
    "name": "sample", "base": { "box": { "length_x": 6, "height": 4 }, "population": { "shape": "pinacoid" } },
    "biperiodic_width": 12, "vary": { "width": [10, "biperiodic"], "replicas": 3, "backend": ["nscd", "bullet"] } })"));
  auto runner = [&](const core::RunConfig& cfg, const fs::path& runDir, const compaction::Deposit&,
                    const study::RunProgressFn&) {
    json r = syntheticResult(cfg, true);
    r["coordination"]["simple"] = (cfg.box.periodicY ? 5.5 : 5.0) + kDelta * (static_cast<double>(cfg.seed) - 2.0);
    std::ofstream(runDir / "result.json") << r.dump();
    if (cfg.backend == "bullet" && !cfg.box.periodicY) {
      fs::create_directories(runDir / study::kSettledFolder);
      std::ofstream(runDir / study::kSettledFolder / "result.json") << r.dump();
    }
    return r;
  };
  study::SweepOptions o;
  o.quiet = true;
  study::runSweep(spec, dir, o, runner, testing::oneGrainDeposit);
  const std::string verdict = verdictOf(slurp(study::writeReport(dir, dir / "report").markdown));
  const auto row = rowCells(verdict, "| MPP: pinacoids x_S = 0, mu_w = 0 | Z_s |");
  REQUIRE(row.size() == 12);
  CHECK(row[2] == "5 ± 0.0012");  // nscd
  CHECK(row[3] == "5 ± 0.0012");  // bullet as it stopped
  CHECK(row[7] == "5 ± 0.0012");  // bullet settled
  CHECK(row[10] == "no: agree");
  fs::remove_all(dir);
}

TEST_CASE("report: a study rerun in part is judged against the whole study's tables (tables-from), as by its runs") {
  const fs::path dir = makeStudy("tables_from", false, false, 0, true);
  const fs::path whole = dir / "report_whole";
  const std::string wholeMd = slurp(study::writeReport(dir, whole).markdown);
  // nscd's runs not run here, as in a settle sweep that leaves them out: no done marker.
  for (const auto& e : fs::directory_iterator(dir / "runs"))
    if (json::parse(slurp(e.path() / "config.json"))["backend"] == "nscd") fs::remove(e.path() / study::kDoneMarker);
  const std::string partMd = slurp(study::writeReport(dir, dir / "report_part").markdown);
  study::ReportOptions o;
  o.tablesFrom = whole / "tables";
  const study::ReportSummary from = study::writeReport(dir, dir / "report_from", o);
  const std::string fromMd = slurp(from.markdown);
  CHECK(from.standIns == 5);  // nscd at W = 4, 5, 10, 20 and biperiodic
  CHECK_THAT(fromMd, Catch::Contains("Not run here, 5 configurations' values are those of the tables in "));
  CHECK_THAT(verdictOf(fromMd), Catch::Contains("nscd's values at 5 widths are another report's tables'"));
  CHECK(rowCells(fromMd, "| MSP: spheres x_S = 0, mu_w = 0 | nscd |")[2] == "0 / 15 (5 widths from tables)");
  // The verdict's rows, fits of nscd's values against Bullet's as stopped and settled, are the
  // whole study's; without the tables nscd's side is missing.
  for (const char* q : {"phi_bulk", "C", "Z_bulk", "C_Z"}) {
    INFO(q);
    const std::string prefix = fmt::format("| MSP: spheres x_S = 0, mu_w = 0 | {} |", q);
    const auto row = rowCells(verdictOf(fromMd), prefix);
    REQUIRE(row.size() == 12);
    CHECK(row == rowCells(verdictOf(wholeMd), prefix));
    CHECK(row != rowCells(verdictOf(partMd), prefix));
  }
  // The tables give nscd's columns as the whole study's, at full precision.
  for (const char* file : {"solid_fraction.csv", "coordination.csv"}) {
    const study::CsvTable a = readTable(whole, file), b = readTable(dir / "report_from", file);
    REQUIRE(a.columns == b.columns);
    REQUIRE(a.rows.size() == b.rows.size());
    for (const char* column : {"nscd_mean", "nscd_std", "nscd_n"}) {
      const std::size_t c =
          static_cast<std::size_t>(std::find(a.columns.begin(), a.columns.end(), column) - a.columns.begin());
      REQUIRE(c < a.columns.size());
      for (std::size_t i = 0; i < a.rows.size(); ++i) CHECK(a.text[i][c] == b.text[i][c]);
    }
  }
  fs::remove_all(dir);
}

TEST_CASE("report with reference values: a reference column beside each quantity, its sources, marks on the figures") {
  const fs::path dir = makeStudy("reference", false);
  study::ReportOptions o;
  o.reference = study::parseReferenceValues(json::parse(R"json({
    "format": "confpack-reference", "version": 1, "description": "test values",
    "families": {
      "MSP": [
        { "phi_bulk": { "value": 0.64, "uncertainty": 0.01, "citation": "Scott and Kilgour, J. Phys. D 2, 863 (1969)" },
          "C": { "value": 0.45, "uncertainty": 0.05, "citation": "made-up example, not a publication" },
          "Z_bulk": { "value": 6, "uncertainty": 0, "citation": "O'Hern et al., Phys. Rev. E 68, 011306 (2003)" } },
        { "mu_w": 0.5,
          "phi_bulk": { "value": 0.1, "uncertainty": 0.1, "citation": "never shown: no series has mu_w 0.5" } }
      ],
      "BSP": { "lambda_L_over_d_avg": { "value": 9, "uncertainty": 1, "citation": "never shown: no BSP series" } }
    }})json"),
                                            "test-reference.json");
  const study::ReportSummary s = study::writeReport(dir, dir / "report", o);
  const std::string md = slurp(s.markdown);
  const std::string html = slurp(s.html);
  const std::size_t summaryAt = md.find("## Summary");
  const std::size_t verdictAt = md.find("## Cross-solver verdict");
  // The columns: each referenced quantity followed by its reference, in the summary only.
  const std::string head =
      "| family | backend | runs at equilibrium / total | bulk d_L / grains | widths fitted | phi_bulk | phi_bulk "
      "reference | C | C reference | phi(W) fit quality | Z_bulk | Z_bulk reference | C_Z | lambda_L/d_avg | "
      "interpenetration |";
  CHECK(md.find(head) > summaryAt);
  CHECK(md.find(head) < verdictAt);
  for (const std::string backend : {"nscd", "bullet"}) {
    INFO(backend);
    const auto row = rowCells(md, "| MSP: spheres x_S = 0, mu_w = 0 | " + backend + " |", summaryAt);
    REQUIRE(row.size() == 15);
    CHECK_THAT(row[5], Catch::StartsWith(backend == "nscd" ? "0.6400 ± " : "0.6300 ± "));
    CHECK(row[6] == "0.64 ± 0.01 [1]");
    CHECK(row[8] == "0.45 ± 0.05 [2]");
    CHECK(row[11] == "6 ± 0 [3]");
  }
  // The sources, numbered as the cells cite them, in both renderings; the file is named.
  CHECK(md.find("Reference values from test-reference.json (test values); [n] in a reference cell is its source:") !=
        std::string::npos);
  CHECK(md.find("- [1] Scott and Kilgour, J. Phys. D 2, 863 (1969)\n- [2] made-up example, not a publication\n- [3] "
                "O'Hern et al., Phys. Rev. E 68, 011306 (2003)\n") != std::string::npos);
  CHECK(html.find("<th>phi_bulk reference</th>") != std::string::npos);
  CHECK(html.find("<td>0.64 ± 0.01 [1]</td>") != std::string::npos);
  CHECK(html.find("<li>[1] Scott and Kilgour, J. Phys. D 2, 863 (1969)</li>") != std::string::npos);
  CHECK(html.find("<li>[3] O'Hern et al.") != std::string::npos);
  CHECK(md.find("never shown") == std::string::npos);
  // The figures' data: the published bulk value at d_L/W = 0 with its uncertainty, the law as a
  // dotted line in the script.
  const fs::path figures = dir / "report" / "figures";
  CHECK(slurp(figures / "phi_vs_invW.csv").find("\nreference MSP x_S=0 mu_w=0 [1],0,0.64,0.01\n") != std::string::npos);
  CHECK(slurp(figures / "phi_vs_invW.gp").find("[0:*] 0.64 - 0.45*x lc 1 dt 3 notitle") != std::string::npos);
  CHECK(slurp(figures / "Z_vs_invW.csv").find("\nreference MSP x_S=0 mu_w=0 [3],0,6,0\n") != std::string::npos);
  CHECK(slurp(figures / "phi_vs_invW.gp").find("squares: reference values") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("report with reference values for none of the study's families says so") {
  const fs::path dir = makeStudy("reference_none", false);
  study::ReportOptions o;
  o.reference = study::parseReferenceValues(
      json::parse(R"({"families": {"MPP": {"phi_bulk": {"value": 0.7, "uncertainty": 0.01, "citation": "c"}}}})"),
      "pinacoids.json");
  const std::string md = slurp(study::writeReport(dir, dir / "report", o).markdown);
  CHECK(md.find("The reference file pinacoids.json gives no value for the families of this study.") !=
        std::string::npos);
  CHECK(md.find("reference |") == std::string::npos);
  CHECK(slurp(dir / "report" / "figures" / "phi_vs_invW.csv").find("reference") == std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("report of a sweep over a setting axis groups by it: summary, runs, tables and a figure against it") {
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_report_axis_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  // Two runs: pinacoids in the biperiodic box at alpha = 60 and 75 degrees, phi rising with alpha.
  const study::SweepSpec spec = study::parseSweepSpec(json::parse(R"({
    "name": "shape", "base": { "box": { "length_x": 6, "height": 4 }, "population": { "shape": "pinacoid" } },
    "vary": { "width": ["biperiodic"], "population.pinacoid.alpha_deg": [60, 75], "backend": "nscd" } })"));
  auto runner = [](const core::RunConfig& cfg, const fs::path& runDir, const compaction::Deposit&,
                   const study::RunProgressFn&) {
    const double alpha = cfg.population.pinacoid.alphaDeg;
    const json r = {{"solid_fraction", 0.5 + alpha / 1000.0},
                    {"coordination",
                     {{"Z", 8.0 + alpha / 100.0}, {"simple", 5.0}, {"double", 2.0 + alpha / 100.0}, {"triple", 1.0}}},
                    {"nematic", {{"bulk", alpha / 100.0}}},
                    {"equilibrium", {{"reached", true}}}};
    std::ofstream(runDir / "result.json") << r.dump();
    return r;
  };
  study::SweepOptions o;
  o.quiet = true;
  study::runSweep(spec, dir, o, runner, testing::oneGrainDeposit);
  const study::ReportSummary s = study::writeReport(dir, dir / "report");
  const std::string md = slurp(s.markdown);
  CHECK(md.find("Beyond W, shape, x_S, mu_w, seed and backend this study varies population.pinacoid.alpha_deg "
                "(alpha_deg): each family below is one combination of its values.") != std::string::npos);
  // One summary row per value, named by it, in numeric order.
  const std::size_t summaryAt = md.find("## Summary");
  const std::size_t at60 = md.find("| MPP: pinacoids x_S = 0, mu_w = 0, alpha_deg = 60 | nscd | 1 / 1 |", summaryAt);
  const std::size_t at75 = md.find("| MPP: pinacoids x_S = 0, mu_w = 0, alpha_deg = 75 | nscd | 1 / 1 |", summaryAt);
  CHECK(at60 != std::string::npos);
  CHECK(at75 != std::string::npos);
  CHECK(at60 < at75);
  // Without confined widths there is no phi_bulk to fit: the summary gives the biperiodic sample's
  // phi and Z, and the pinacoids' contact types and nematic order, each with its definition.
  CHECK(
      md.find("| family | backend | runs at equilibrium / total | bulk d_L / grains | widths fitted | phi | Z | Z_s | "
              "Z_d | Z_t | S |\n",
              summaryAt) != std::string::npos);
  CHECK(
      md.find(
          "| MPP: pinacoids x_S = 0, mu_w = 0, alpha_deg = 75 | nscd | 1 / 1 | - | - | 0.575 (1 run) | 8.75 (1 run) | "
          "5 (1 run) | 2.75 (1 run) | 1 (1 run) | 0.75 (1 run) |",
          summaryAt) != std::string::npos);
  CHECK(md.find("- Z_t: pinacoids: triple contacts per grain (face-face), on the biperiodic sample") !=
        std::string::npos);
  // The runs say their value.
  CHECK(md.find("| MPP xS=0 W=bi20 mu=0 s1 nscd alpha_deg=75 | done |") != std::string::npos);
  // tables/: a column for the setting, by its path, a row per value.
  const study::CsvTable phi = readTable(dir / "report", "solid_fraction.csv");
  const auto col = std::find(phi.columns.begin(), phi.columns.end(), "population.pinacoid.alpha_deg");
  REQUIRE(col != phi.columns.end());
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(phi.columns.begin(), phi.columns.end(), name) - phi.columns.begin());
  };
  REQUIRE(phi.rows.size() == 2);
  CHECK(phi.text[0][column("population.pinacoid.alpha_deg")] == "60");
  CHECK(phi.rows[0][column("nscd_mean")] == Approx(0.56));
  CHECK(phi.text[1][column("population.pinacoid.alpha_deg")] == "75");
  CHECK(phi.rows[1][column("nscd_mean")] == Approx(0.575));
  // phi and Z against the setting: one line through both values.
  CHECK(md.find("## Solid fraction and coordination against alpha_deg") != std::string::npos);
  const std::string csv = slurp(dir / "report" / "figures" / "phi_vs_alpha_deg.csv");
  CHECK(csv ==
        "series,x,y,err\nMPP x_S=0 mu_w=0 W=biperiodic (20) nscd,60,0.56,0\n"
        "MPP x_S=0 mu_w=0 W=biperiodic (20) nscd,75,0.575,0\n");
  CHECK(fs::exists(dir / "report" / "figures" / "Z_vs_alpha_deg.csv"));
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT")) fs::remove_all(dir);
}

TEST_CASE("report: a family's lambda_L from more replicas run apart (lambda-from), refused for another configuration") {
  const fs::path dir = makeStudy("lambda_from", false);
  const fs::path more = makeReplicaSweep("lambda_more", 10.0, 4.0, 2.0, 6);
  const fs::path other = makeReplicaSweep("lambda_other", 10.0, 5.0, 2.0, 3);
  const fs::path narrow = makeReplicaSweep("lambda_narrow", 5.0, 4.0, 2.0, 3);
  study::checkLambdaSources(dir, {more, narrow});
  try {
    study::checkLambdaSources(dir, {more, other});
    FAIL("a sweep of another box height was taken");
  } catch (const std::invalid_argument& e) {
    CHECK_THAT(e.what(), Catch::Contains("--lambda-from " + other.string() + ": run r0000"));
    CHECK_THAT(e.what(), Catch::Contains("(first difference: box/height)"));
  }
  study::ReportOptions o;
  o.gnuplot.clear();
  o.lambdaFrom = {narrow, more};
  const fs::path out = dir / "report_more";
  study::writeReport(dir, out, o);
  // nscd's sample at W = 10 is the six replicas of the other sweep, whose layering decays over 2 d_L;
  // Bullet's stays the study's three at 1.5 d_L.
  const study::CsvTable t = readTable(out, "lambda.csv");
  const auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(t.columns.begin(), t.columns.end(), name) - t.columns.begin());
  };
  REQUIRE(t.rows.size() == 2);
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const bool nscd = t.text[i][col("backend")] == "nscd";
    CHECK(t.rows[i][col("seeds")] == (nscd ? 6.0 : 3.0));
    CHECK(t.rows[i][col("lambda_L")] == Approx(nscd ? 2.0 : 1.5).margin(0.01));
  }
  const std::string md = slurp(out / "report.md");
  CHECK_THAT(md, Catch::Contains("- MSP: spheres x_S = 0, mu_w = 0 (nscd): its 6 replicas from " + more.string()));
  CHECK_THAT(md, Catch::Contains("- " + narrow.string() + ": none, it has no finished runs of the study's families"));
  if (!std::getenv("CONFPACK_KEEP_TEST_OUTPUT"))
    for (const fs::path& d : {dir, more, other, narrow}) fs::remove_all(d);
}
