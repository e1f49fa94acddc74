// `confpack-bench --case scaling` (bench/bench.hpp): loaded piles timed with both backends and the
// exponents fitted, run through the real binary (CONFPACK_BENCH_BINARY) as a user runs it.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using confpack::testing::CommandResult;
using confpack::testing::ConfpackSession;
using nlohmann::json;

// The scaling series times the cost per step of a pile that carries its weight (the regime of a
// whole compaction), not of the first steps after the deposit, where grains barely touch (0.17
// contact rows per grain over steps 200 to 400 of 2,000 spheres, against 3.3 after 4 t0).
TEST_CASE("bench --case scaling times loaded piles with both backends and fits the exponents") {
  ConfpackSession s("bench_scaling", CONFPACK_BENCH_BINARY);
  // glibc's tunables change the memory the solver runs on (2 MiB pages): the bench records them.
  const char* tunables = "glibc.malloc.hugetlb=1";
  REQUIRE(::setenv("GLIBC_TUNABLES", tunables, 1) == 0);
  const CommandResult r =
      s.run("--case scaling --scale 0.5 --scaling-sizes 300 450 --scaling-steps 20 --scaling-fall 3 --out b.json");
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

// The rest series: time to equilibrium against n, nscd only, in the scaling series' box. Its
// exponent is the least-squares slope through the points at rest, recomputed here from them.
TEST_CASE("bench --case rest compacts each size to equilibrium and fits t_rest ~ n^k through the points at rest") {
  ConfpackSession s("bench_rest", CONFPACK_BENCH_BINARY);
  const CommandResult r =
      s.run("--case rest --scale 0.4 --rest-sizes 200 400 --protocol quasi-static --time-limit 40 --out r.json");
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("bench: case rest\n") != std::string::npos);
  const json cases = json::parse(confpack::testing::slurp(s.dir / "r.json"))["cases"];
  const json& points = cases["rest"];
  REQUIRE(points.size() == 2);
  double logN[2], logT[2];
  for (int k = 0; k < 2; ++k) {
    const json& p = points[k];
    INFO("point " << k);
    CHECK(p["equilibrium_reached"] == true);
    CHECK(p["stages"].contains("quasi_static"));  // the protocol asked for
    const double n = p["n_grains"].get<double>();
    CHECK(std::abs(n - 200.0 * (k + 1)) < 0.1 * 200.0 * (k + 1));  // the stretched box holds about n
    logN[k] = std::log(n);
    logT[k] = std::log(p["wall_s"].get<double>());
    CHECK(p["step_cpu_s"].get<double>() > 0.0);
  }
  const json& e = cases["rest_exponent"];
  CHECK(e["points_at_rest"] == 2);
  // Through two points the least-squares slope is the slope of the line between them.
  CHECK(e["wall"].get<double>() == Approx((logT[1] - logT[0]) / (logN[1] - logN[0])).epsilon(1e-12));
  CHECK(std::isfinite(e["cpu"].get<double>()));
  // The targets this run measured, printed with their figures: at 400 grains the 30,400-sphere
  // one is not shown.
  const json targets = json::parse(confpack::testing::slurp(s.dir / "r.json"))["targets"];
  REQUIRE(targets.size() == 2);
  CHECK(targets[0]["met"].is_null());
  CHECK(r.err.find("target rest: 30,400 spheres at equilibrium in at most 30 minutes: ") != std::string::npos);
  CHECK(r.err.find("(not judged by this run)") != std::string::npos);
}
