// `confpack bench`: the Google Benchmark micro-benchmarks of the nscd phases (--micro) and the
// scaling series, run through the real binary (CONFPACK_BINARY) as a user runs them.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct Run {
  int code = -1;
  std::string out, err;
};

/// A scratch directory per test case, removed at the end.
struct Scratch {
  fs::path dir;
  explicit Scratch(const std::string& name)
      : dir(fs::temp_directory_path() / ("confpack_test_micro_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() { fs::remove_all(dir); }
  /// Runs `confpack <args>` in the scratch directory; stdout and stderr are captured outside it,
  /// so that the directory shows only what confpack wrote.
  Run run(const std::string& args) const {
    const fs::path outFile = dir.string() + ".stdout", errFile = dir.string() + ".stderr";
    const std::string cmd = "cd '" + dir.string() + "' && '" + std::string(CONFPACK_BINARY) + "' " + args + " > '" +
                            outFile.string() + "' 2> '" + errFile.string() + "'";
    const int status = std::system(cmd.c_str());
    Run r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = confpack::testing::slurp(outFile);
    r.err = confpack::testing::slurp(errFile);
    fs::remove(outFile);
    fs::remove(errFile);
    return r;
  }
  bool empty() const { return fs::is_empty(dir); }
};

int lineCount(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

}  // namespace

TEST_CASE("bench --micro writes Google Benchmark's JSON with a positive sphere-sphere rate") {
  Scratch s("run");
  const Run r = s.run(
      "bench --micro --micro-filter 'NarrowPhase/sphere-sphere' --micro-repetitions 1 "
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
  Scratch s("reps");
  const Run r = s.run(
      "bench --micro --micro-filter 'NarrowPhase/sphere-wall' --micro-repetitions 2 "
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
  Scratch s("bad");
  for (const char* args :
       {"bench --micro --case msp-w10 --out m.json", "bench --micro --scale 0.5 --out m.json",
        "bench --micro --threads 2 --out m.json", "bench --micro --micro-repetitions 0 --out m.json",
        "bench --micro --micro-repetitions two --out m.json", "bench --micro --micro-min-time -1 --out m.json",
        "bench --micro --micro-filter 'NoSuchBenchmark' --out m.json", "bench --micro --micro-filter '(' --out m.json",
        "bench --micro-filter 'NarrowPhase' --out m.json", "bench --micro --out no/such/dir/m.json"}) {
    INFO(args);
    const Run r = s.run(args);
    CHECK(r.code == 2);
    CHECK(lineCount(r.err) == 1);
    CHECK(r.out.empty());
    CHECK(s.empty());
  }
}

TEST_CASE("bench --micro times the broad phase on a deposit and a pile, and both solvers over a real contact network") {
  Scratch s("sweep");
  const Run r = s.run(
      "bench --micro --micro-filter '/2000$' --micro-repetitions 1 --micro-min-time 0.01 "
      "--out m.json");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const json report = json::parse(confpack::testing::slurp(s.dir / "m.json"));
  std::map<std::string, json> byName;
  for (const json& b : report["benchmarks"]) byName[b["run_name"].get<std::string>()] = b;
  REQUIRE(byName.size() == 4);
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
}

// The scaling series times the cost per step of a pile that carries its weight (the regime of a
// whole compaction), not of the first steps after the deposit, where grains barely touch (0.17
// contact rows per grain over steps 200 to 400 of 2,000 spheres, against 3.3 after 4 t0).
TEST_CASE("bench --case scaling times loaded piles with both backends and fits the exponents") {
  Scratch s("scaling");
  // glibc's tunables change the memory the solver runs on (2 MiB pages): the bench records them.
  const char* tunables = "glibc.malloc.hugetlb=1";
  REQUIRE(::setenv("GLIBC_TUNABLES", tunables, 1) == 0);
  const Run r = s.run(
      "bench --case scaling --scale 0.5 --scaling-sizes 300 450 --scaling-steps 20 --scaling-fall 3 --out b.json");
  ::unsetenv("GLIBC_TUNABLES");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const json machine = json::parse(confpack::testing::slurp(s.dir / "b.json"))["machine"];
  CHECK(machine["glibc_tunables"] == tunables);
  const json& thp = machine["transparent_hugepage"];
  CHECK((thp.is_null() || thp == "always" || thp == "madvise" || thp == "never"));
  // Progress on stderr (a file here, so plain lines): which case runs, then each compaction's own
  // progress (the first report of a compaction is always printed), led by the case.
  CHECK(r.err.find("bench: case scaling\n") != std::string::npos);
  CHECK(r.err.find("scaling n=450 nscd t=") != std::string::npos);
  CHECK(r.err.find("scaling n=450 bullet t=") != std::string::npos);
  const json cases = json::parse(confpack::testing::slurp(s.dir / "b.json"))["cases"];
  const json& points = cases["scaling"];
  REQUIRE(points.size() == 2);
  for (const json& point : points) {
    const double n = point["n_grains"].get<double>();
    CHECK(n > 250.0);
    for (const char* backend : {"nscd", "bullet"}) {
      INFO(backend << " at n = " << n);
      const json& b = point[backend];
      CHECK(b["time_per_step_s"].get<double>() > 0.0);
      CHECK(b["solve_s_per_step"].get<double>() <= b["time_per_step_s"].get<double>());
      // One thread: its CPU time cannot exceed the wall time of the same steps (clock granularity aside).
      CHECK(b["cpu_per_step_s"].get<double>() > 0.0);
      CHECK(b["cpu_per_step_s"].get<double>() <= 1.02 * b["time_per_step_s"].get<double>() + 1e-5);
      CHECK(b["sweeps_per_step"].get<double>() >= 1.0);
      // A pile in contact: a settled frictionless sphere pile has about 3 rows per grain
      // (isostatic Z = 6); it is still loading after 3 t0.
      const double rowsPerGrain = b["contact_rows"].get<double>() / n;
      CHECK(rowsPerGrain > 1.5);
      CHECK(rowsPerGrain < 4.0);
    }
  }
  for (const char* backend : {"nscd", "bullet"}) {
    CHECK(std::isfinite(cases["scaling_exponent"][backend].get<double>()));
    CHECK(std::isfinite(cases["scaling_exponent"]["per_sweep"][backend].get<double>()));
    CHECK(std::isfinite(cases["scaling_exponent"]["cpu"][backend].get<double>()));
  }
}
