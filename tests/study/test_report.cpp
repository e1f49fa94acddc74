// Study report: statistics over replicas, backend differences, the phi(W) fit on synthetic data
// with known phi_bulk and C, and missing/failed runs shown as such.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "study/report.hpp"
#include "study/sweep.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using nlohmann::json;

namespace {

using confpack::testing::slurp;

// Synthetic physics: phi = phi_bulk - C / W with a replica offset delta (s - 2) for seeds 1, 2, 3,
// so that the replica mean is exactly on the law and the replica std is exactly delta.
// nscd: phi_bulk = 0.64, C = 0.5; bullet: phi_bulk = 0.63, C = 0.4. Z = 6 - 1.2 / W for both.
constexpr double kDelta = 0.002;

json syntheticResult(const core::RunConfig& cfg) {
  const bool nscd = cfg.backend == "nscd";
  const double phiBulk = nscd ? 0.64 : 0.63;
  const double c = nscd ? 0.5 : 0.4;
  const double offset = kDelta * (static_cast<double>(cfg.seed) - 2.0);
  const double phi = (cfg.box.periodicY ? phiBulk : phiBulk - c / cfg.box.width) + offset;
  const double z = (cfg.box.periodicY ? 6.0 : 6.0 - 1.2 / cfg.box.width) + offset;
  return {
      {"n_grains", 100},
      {"backend", cfg.backend},
      {"seed", cfg.seed},
      {"solid_fraction", phi},
      {"coordination", {{"Z", z}, {"simple", z}, {"double", nullptr}, {"triple", nullptr}, {"rattler_fraction", 0.05}}},
      {"interpenetration_percent", {{"exact", nscd ? 0.01 : 0.2}, {"lattice_min", nullptr}, {"lattice_max", nullptr}}},
      {"equilibrium",
       {{"reached", true}, {"max_force_ratio", 1e-5}, {"max_moment_ratio", 1e-5}, {"max_kinetic_ratio", 1e-9}}},
      {"anisotropy", 0.1},
      {"nematic", {{"bulk", nullptr}, {"boundary", nullptr}}},
      {"profile_fit", {{"phi_bulk", phiBulk}, {"lambda_L", 1.0 + 0.1 * cfg.population.smallFraction / 10.0}}},
      {"timing", {{"wall_s", 1.5}, {"steps", 1000}, {"iterations", 20000}}}};
}

fs::path makeStudy(const std::string& name, bool withFailures) {
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_report_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const json doc = json::parse(R"({
    "name": "synthetic",
    "base": { "box": { "length_x": 6, "height": 4 } },
    "biperiodic_width": 12,
    "vary": { "width": [4, 5, 10, 20, "biperiodic"], "replicas": 3, "backend": ["nscd", "bullet"] }
  })");
  const study::SweepSpec spec = study::parseSweepSpec(doc);
  auto runner = [&](const core::RunConfig& cfg, const fs::path& runDir, const core::Deposit&,
                    const study::RunProgressFn&) {
    // bullet at W = 20 fails for every seed: its cell must read "missing", not vanish.
    if (withFailures && cfg.backend == "bullet" && cfg.box.width == 20.0 && !cfg.box.periodicY)
      throw std::runtime_error("solver diverged");
    json r = syntheticResult(cfg);
    // Seed 3 at W = 10 is not at rest: nscd's finisher ran out of steps, Bullet hit its time limit.
    if (withFailures && cfg.box.width == 10.0 && !cfg.box.periodicY && cfg.seed == 3) {
      r["equilibrium"]["reached"] = false;
      if (cfg.backend == "nscd") r["timing"]["stages"] = {{"quasi_static", {{"steps", 3000}}}};
    }
    std::ofstream(runDir / "result.json") << r.dump();
    std::ofstream csv(runDir / "phi_y.csv");
    csv << "# seed " << cfg.seed << "\ny,phi\n";
    for (int i = 0; i < 10; ++i) csv << 0.1 * i << ',' << 0.6 + 0.01 * std::cos(6.0 * i) << '\n';
    return r;
  };
  auto depositor = [](const core::RunConfig& cfg) {
    core::Deposit d;
    core::Grain g;
    g.position = core::Vec3(1.0, 0.5 * cfg.box.width, 0.5);
    d.grains.push_back(g);
    d.placeholders.push_back(g.position);
    return d;
  };
  study::SweepOptions o;
  o.quiet = true;
  study::runSweep(spec, dir, o, runner, depositor);
  if (withFailures) {
    // One run interrupted: its folder exists without a done marker.
    fs::remove(dir / "runs" / "r0000" / study::kDoneMarker);
  }
  return dir;
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
  // Per-configuration cell: mean +- std over 3 replicas; W = 10 nscd phi = 0.64 - 0.05 = 0.59.
  CHECK(md.find("0.59 ± 0.002 (n=3)") != std::string::npos);
  // Difference at W = 5: (0.64 - 0.1) - (0.63 - 0.08) = -0.01, uncertainty sqrt(2 delta^2 / 3) = 0.00163.
  CHECK(md.find("| 0.54 ± 0.002 (n=3) | 0.55 ± 0.002 (n=3) | -0.01 ± 0.0016 (*) |") != std::string::npos);
  // Quantities present in result.json all have tables; nulls are reported as not applicable.
  for (const char* k : {"### solid_fraction", "### coordination/Z", "### coordination/rattler_fraction",
                        "### interpenetration_percent/exact", "### anisotropy", "### equilibrium/max_force_ratio",
                        "### profile_fit/lambda_L", "### timing/wall_s"})
    CHECK(md.find(k) != std::string::npos);
  CHECK(md.find("nematic/bulk") != std::string::npos);
  CHECK(md.find("Not applicable") != std::string::npos);
  CHECK(md.find("Every run finished") != std::string::npos);
  // Figures with their data next to them; the HTML inlines the SVG.
  CHECK(fs::exists(dir / "report" / "figures" / "phi_vs_invW.csv"));
  CHECK(fs::exists(dir / "report" / "figures" / "phi_vs_invW.gp"));
  if (s.gnuplotUsed) {
    CHECK(fs::exists(dir / "report" / "figures" / "phi_vs_invW.svg"));
    CHECK(html.find("<svg") != std::string::npos);
    CHECK(md.find("![") != std::string::npos);
  }
  CHECK(md.find("Profiles") != std::string::npos);
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
  CHECK(md.find("| r0000 |") != std::string::npos);
  CHECK(md.find("missing: not run or interrupted") != std::string::npos);
  // Each unequilibrated run says what stopped it.
  CHECK(md.find("nscd | done, NOT equilibrated | 0.5920 | 1.5 | finisher not at rest after 3000 steps |") !=
        std::string::npos);
  CHECK(md.find("bullet | done, NOT equilibrated | 0.5920 | 1.5 | stopped at the time limit |") != std::string::npos);
  // bullet at W = 20 has no replica: the cell reads "missing".
  CHECK(md.find("| MSP | 0 | 20 | 0 | 0.615 ± 0.002 (n=3) | missing |") != std::string::npos);
  // nscd at W = 4 lost seed 1 (r0000): n = 2 there, mean of seeds 2 and 3.
  CHECK(md.find("0.516 ± 0.0014 (n=2)") != std::string::npos);
  // The fits still run on the widths that have data (bullet: 3 widths).
  CHECK(md.find("| MSP x_S=0 mu_w=0 | bullet | 3 | 0.6300 ± ") != std::string::npos);
  fs::remove_all(dir);
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
