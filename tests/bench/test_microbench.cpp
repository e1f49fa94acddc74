// `confpack-bench --micro` (bench/microbench.hpp): the Google Benchmark micro-benchmarks of the nscd
// phases, run through the real binary (CONFPACK_BENCH_BINARY) as a user runs them.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using confpack::testing::CommandResult;
using confpack::testing::ConfpackSession;
using confpack::testing::lineCount;
using nlohmann::json;

TEST_CASE("bench --micro writes Google Benchmark's JSON with a positive sphere-sphere rate") {
  ConfpackSession s("micro_run", CONFPACK_BENCH_BINARY);
  const CommandResult r = s.run(
      "--micro --micro-filter 'NarrowPhase/sphere-sphere' --micro-repetitions 1 "
      "--micro-min-time 0.01 --out m.json");
  INFO(r.err);
  REQUIRE(r.code == 0);
  // The console table goes to stdout.
  CHECK(r.out.find("NarrowPhase/sphere-sphere") != std::string::npos);
  const json report = json::parse(confpack::testing::slurp(s.dir / "m.json"));
  REQUIRE(report.contains("benchmarks"));
  int found = 0;
  for (const json& b : report["benchmarks"]) {
    // The filter selects this benchmark alone.
    CHECK(b["run_name"] == "NarrowPhase/sphere-sphere");
    if (b["run_name"] != "NarrowPhase/sphere-sphere") continue;
    ++found;
    CHECK(b["items_per_second"].get<double>() > 0.0);
    CHECK(b["iterations"].get<long>() >= 1);
    // Every pose of the fixture is a contact with one point.
    CHECK(b["points_per_pair"].get<double>() == Approx(1.0));
  }
  CHECK(found == 1);
  // Atomic write: only the report is left in the directory, no temporary file.
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(s.dir)) ++entries;
  CHECK(entries == 1);
}

TEST_CASE("bench --micro with repetitions reports the aggregates only, median included") {
  ConfpackSession s("micro_reps", CONFPACK_BENCH_BINARY);
  const CommandResult r = s.run(
      "--micro --micro-filter 'NarrowPhase/sphere-wall' --micro-repetitions 2 "
      "--micro-min-time 0.005 --out m.json");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const json report = json::parse(confpack::testing::slurp(s.dir / "m.json"));
  bool median = false;
  for (const json& b : report["benchmarks"]) {
    CHECK(b["run_type"] == "aggregate");
    if (b["aggregate_name"] == "median") {
      median = true;
      CHECK(b["items_per_second"].get<double>() > 0.0);
    }
  }
  CHECK(median);
}

TEST_CASE("bench --micro refuses bad input with one line, exit 2 and nothing written") {
  ConfpackSession s("micro_bad", CONFPACK_BENCH_BINARY);
  for (const char* args :
       {"--micro --case msp-w10 --out m.json", "--micro --scale 0.5 --out m.json", "--micro --threads 2 --out m.json",
        "--micro --micro-repetitions 0 --out m.json", "--micro --micro-repetitions two --out m.json",
        "--micro --micro-min-time -1 --out m.json", "--micro --micro-filter 'NoSuchBenchmark' --out m.json",
        "--micro --micro-filter '(' --out m.json", "--micro-filter 'NarrowPhase' --out m.json",
        "--micro --out no/such/dir/m.json"}) {
    INFO(args);
    const CommandResult r = s.run(args);
    CHECK(r.code == 2);
    CHECK(lineCount(r.err) == 1);
    CHECK(r.out.empty());
    CHECK(s.empty());
  }
}

TEST_CASE("bench --micro times the broad phase on a deposit and a pile, and both solvers over a real contact network") {
  ConfpackSession s("micro_sweep", CONFPACK_BENCH_BINARY);
  const CommandResult r = s.run(
      "--micro --micro-filter '/2000$' --micro-repetitions 1 --micro-min-time 0.01 "
      "--out m.json");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const json report = json::parse(confpack::testing::slurp(s.dir / "m.json"));
  std::map<std::string, json> byName;
  for (const json& b : report["benchmarks"]) byName[b["run_name"].get<std::string>()] = b;
  REQUIRE(byName.size() == 6);
  REQUIRE(byName.count("BroadPhase/spheres/2000") == 1);
  REQUIRE(byName.count("GaussSeidelSweep/spheres/2000") == 1);
  const json& broad = byName["BroadPhase/spheres/2000"];
  CHECK(broad["items_per_second"].get<double>() > 0.0);
  // A geometric deposit: grains replaced their placeholders, so most pairs are still apart, but the
  // broad phase does find some.
  CHECK(broad["pairs_per_grain"].get<double>() > 0.0);
  CHECK(broad["pairs_per_grain"].get<double>() < 6.0);
  // The settled pile of the solver benchmarks is dense: its broad phase finds many more pairs.
  REQUIRE(byName.count("BroadPhase/pile/2000") == 1);
  const json& pile = byName["BroadPhase/pile/2000"];
  CHECK(pile["items_per_second"].get<double>() > 0.0);
  CHECK(pile["pairs_per_grain"].get<double>() > 2.5);
  CHECK(pile["pairs_per_grain"].get<double>() > 5.0 * broad["pairs_per_grain"].get<double>());
  const json& sweep = byName["GaussSeidelSweep/spheres/2000"];
  CHECK(sweep["items_per_second"].get<double>() > 0.0);
  // A connected pile: Z about 6 grain-grain contacts (3 rows per grain) plus the floor rows.
  CHECK(sweep["rows_per_grain"].get<double>() > 2.5);
  CHECK(sweep["rows_per_grain"].get<double>() < 4.5);
  // MPRGP on the same rows: every timed solve runs its fixed 50 iterations.
  REQUIRE(byName.count("MprgpIteration/spheres/2000") == 1);
  const json& mprgp = byName["MprgpIteration/spheres/2000"];
  CHECK(mprgp["items_per_second"].get<double>() > 0.0);
  CHECK(mprgp["iterations_per_solve"].get<double>() == Approx(50.0));
  CHECK(mprgp["rows_per_grain"].get<double>() == Approx(sweep["rows_per_grain"].get<double>()));
  // Whole solves to 1e-10: the exact free-block preconditioner takes fewer iterations than the
  // sweeps, each with a factorisation or a change of it.
  REQUIRE(byName.count("MprgpSolve/sgs/spheres/2000") == 1);
  REQUIRE(byName.count("MprgpSolve/cholesky/spheres/2000") == 1);
  const json& sgsSolve = byName["MprgpSolve/sgs/spheres/2000"];
  const json& exactSolve = byName["MprgpSolve/cholesky/spheres/2000"];
  CHECK(exactSolve["iterations_per_solve"].get<double>() < sgsSolve["iterations_per_solve"].get<double>());
  CHECK(exactSolve["factor_changes_per_solve"].get<double>() >= 1.0);
}

TEST_CASE("bench --micro --micro-pile times MPRGP's solve of a given packing's step, and refuses a missing file") {
  // A small compacted pile (91 spheres after 6 t0), the user's: both preconditioners solve its
  // step, on the same rows. With the free block's exact inverse the solve needs a few times fewer
  // iterations than with SGS (23 against 119 on this pile): a contact network's soft modes are
  // what SGS leaves to the Krylov iterations, and the exact inverse removes them.
  ConfpackSession s("micro_pile", CONFPACK_BENCH_BINARY);
  const ConfpackSession maker("micro_pile_run");
  REQUIRE(maker.run("run --length-x 4 --width 4 --periodic-y --height 5 --time-limit 6 --out p -q").code == 0);
  const fs::path packing = maker.dir / "p" / "packing.json";
  const CommandResult r =
      s.run("--micro --micro-pile '" + packing.string() +
            "' --micro-filter 'Solve/.*/pile' --micro-repetitions 1 --micro-min-time 0.01 --out m.json");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const json report = json::parse(confpack::testing::slurp(s.dir / "m.json"));
  std::map<std::string, json> byName;
  for (const json& b : report["benchmarks"]) byName[b["run_name"].get<std::string>()] = b;
  REQUIRE(byName.size() == 2);
  const json& sgs = byName["MprgpSolve/sgs/pile"];
  const json& exact = byName["MprgpSolve/cholesky/pile"];
  CHECK(sgs["rows"].get<double>() > 0.0);
  CHECK(exact["rows"].get<double>() == sgs["rows"].get<double>());
  CHECK(sgs["iterations_per_solve"].get<double>() >= 30.0);
  CHECK(exact["iterations_per_solve"].get<double>() < sgs["iterations_per_solve"].get<double>() / 3.0);
  // The creep block's target is judged from the two solves' times, in the report and on stdout.
  REQUIRE(report["targets"].size() == 1);
  const json& target = report["targets"][0];
  CHECK(target["met"] == (sgs["real_time"].get<double>() >= 5.0 * exact["real_time"].get<double>()));
  CHECK(target["figure"].get<std::string>().rfind("cholesky ", 0) == 0);
  CHECK(r.out.find("bench: target creep block (--micro-pile)") != std::string::npos);

  const CommandResult missing = s.run("--micro --micro-pile nowhere.json --out m2.json");
  CHECK(missing.code == 2);
  CHECK(lineCount(missing.err) == 1);
  CHECK(missing.err.find("--micro-pile: nowhere.json") != std::string::npos);
  CHECK_FALSE(fs::exists(s.dir / "m2.json"));
}

namespace {

// The numbers of a dumped CSV file, a row a line, without its header.
std::vector<std::vector<double>> csvNumbers(const fs::path& file) {
  std::istringstream in(confpack::testing::slurp(file));
  std::string line;
  std::getline(in, line);  // the header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> values;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) values.push_back(std::stod(cell));
    rows.push_back(values);
  }
  return rows;
}

}  // namespace

TEST_CASE("bench --micro-dump writes a pile's step whose dumped impulses solve the dumped problem") {
  // The contact problem from the files alone: u = G (v_free + M^-1 G^T r), w = u + c. The solution
  // MPRGP reached to 1e-10 must satisfy it: r >= 0, w >= 0, r.w = 0, so a row or body written
  // wrongly (a sign, a column, another step's velocities) shows as a violated complementarity.
  ConfpackSession s("micro_dump", CONFPACK_BENCH_BINARY);
  const ConfpackSession maker("micro_dump_run");
  REQUIRE(maker.run("run --length-x 4 --width 4 --periodic-y --height 5 --time-limit 6 --out p -q").code == 0);
  const std::string packing = (maker.dir / "p" / "packing.json").string();
  const CommandResult r = s.run("--micro --micro-pile '" + packing + "' --micro-dump block");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const json block = json::parse(confpack::testing::slurp(s.dir / "block" / "block.json"));
  const std::vector<std::vector<double>> rows = csvNumbers(s.dir / "block" / "rows.csv");
  const std::vector<std::vector<double>> bodies = csvNumbers(s.dir / "block" / "bodies.csv");
  REQUIRE(rows.size() == block["rows"].get<std::size_t>());
  REQUIRE(bodies.size() == block["bodies"].get<std::size_t>());
  REQUIRE(rows.size() > 100);
  CHECK(block["mprgp_residual"].get<double>() <= 1e-10);

  // The velocities after the impulses, body by body (the last body, the walls, stays still).
  const std::size_t walls = bodies.size() - 1;
  CHECK(bodies[walls][0] == 0.0);
  std::vector<std::array<double, 6>> v(bodies.size());
  for (std::size_t i = 0; i < bodies.size(); ++i)
    for (int k = 0; k < 6; ++k) v[i][k] = bodies[i][10 + k];
  auto apply = [&](std::size_t body, double sign, const double* n, const double* arm, double impulse) {
    for (int d = 0; d < 3; ++d) v[body][d] += sign * impulse * bodies[body][0] * n[d];
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) v[body][3 + d] += sign * impulse * bodies[body][1 + 3 * d + e] * arm[e];
  };
  double largest = 0.0;
  for (const std::vector<double>& row : rows) {
    REQUIRE(row.size() == 13);
    CHECK(row[12] >= 0.0);
    largest = std::max(largest, row[12]);
    apply(static_cast<std::size_t>(row[1]), 1.0, &row[2], &row[8], row[12]);   // +r n on b
    apply(static_cast<std::size_t>(row[0]), -1.0, &row[2], &row[5], row[12]);  // -r n on a
  }
  REQUIRE(largest > 0.0);
  double minW = 0.0, complementarity = 0.0;
  for (const std::vector<double>& row : rows) {
    const auto& va = v[static_cast<std::size_t>(row[0])];
    const auto& vb = v[static_cast<std::size_t>(row[1])];
    double u = 0.0;
    for (int d = 0; d < 3; ++d) u += row[2 + d] * (vb[d] - va[d]) + row[8 + d] * vb[3 + d] - row[5 + d] * va[3 + d];
    const double w = u + row[11];
    minW = std::min(minW, w);
    complementarity = std::max(complementarity, std::abs(w * row[12]));
  }
  // Velocities of order g dt = 0.05 and impulses of order m g dt: the solve's 1e-10 leaves
  // violations many orders below them.
  CHECK(minW > -1e-8);
  CHECK(complementarity < 1e-8 * largest);

  // Refused with one line and exit 2: an existing folder, and a dump without a pile.
  const CommandResult again = s.run("--micro --micro-pile '" + packing + "' --micro-dump block");
  CHECK(again.code == 2);
  CHECK(lineCount(again.err) == 1);
  CHECK(again.err.find("--micro-dump block: already exists") != std::string::npos);
  for (const std::string& bad :
       {std::string("--micro --micro-dump other"),
        "--micro --micro-pile '" + packing + "' --micro-dump other --micro-filter 'Solve/.*/pile'",
        std::string("--micro --micro-pile nowhere.json --micro-dump other")}) {
    const CommandResult refused = s.run(bad);
    INFO(bad);
    CHECK(refused.code == 2);
    CHECK(lineCount(refused.err) == 1);
    CHECK_FALSE(fs::exists(s.dir / "other"));
  }
}
