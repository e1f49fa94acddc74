// benchTargets and microTargets (bench/bench.hpp, bench/microbench.hpp): each speed target judged
// from the figures of a bench run, and left undecided where the run was not at the target's size.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "bench/bench.hpp"
#include "bench/microbench.hpp"

using confpack::bench::BenchDef;
using confpack::bench::benchTargets;
using nlohmann::json;

namespace {

json compared(double nscdWall, bool reached, double damping = 0.0) {
  return {{"nscd", {{"wall_s", nscdWall}, {"equilibrium_reached", reached}, {"settings", {{"damping", damping}}}}}};
}

const json& only(const json& targets, const std::string& prefix) {
  for (const json& t : targets)
    if (t["target"].get<std::string>().rfind(prefix, 0) == 0) return t;
  FAIL("no target starting with " << prefix);
  static const json none;
  return none;
}

}  // namespace

TEST_CASE("bench targets: msp-w10 is met at rest within 60 s on one thread, and only there") {
  const BenchDef def;  // scale 1, one thread
  CHECK(only(benchTargets(def, {{"msp-w10", compared(59.0, true)}}), "msp-w10")["met"] == true);
  CHECK(only(benchTargets(def, {{"msp-w10", compared(61.0, true)}}), "msp-w10")["met"] == false);
  const json late = only(benchTargets(def, {{"msp-w10", compared(30.0, false)}}), "msp-w10");
  CHECK(late["met"] == false);
  CHECK(late["figure"] == "not at rest after 30.0 s");
  BenchDef small = def;
  small.scale = 0.5;  // a smaller pile says nothing of the target's
  CHECK(only(benchTargets(small, {{"msp-w10", compared(10.0, true)}}), "msp-w10")["met"].is_null());
  BenchDef two = def;
  two.threads = 2;
  CHECK(only(benchTargets(two, {{"msp-w10", compared(10.0, true)}}), "msp-w10")["met"].is_null());
}

TEST_CASE("bench targets: msp-w10's step on the way, at rest within 180 s, is judged beside the 60 s target") {
  const BenchDef def;
  const std::string way = "msp-w10: nscd at equilibrium in at most 180 s";
  const json at120 = benchTargets(def, {{"msp-w10", compared(120.0, true)}});
  CHECK(only(at120, "msp-w10")["met"] == false);  // the 60 s target
  CHECK(only(at120, way)["met"] == true);
  CHECK(only(benchTargets(def, {{"msp-w10", compared(181.0, true)}}), way)["met"] == false);
  CHECK(only(benchTargets(def, {{"msp-w10", compared(100.0, false)}}), way)["met"] == false);
  BenchDef two = def;
  two.threads = 2;
  CHECK(only(benchTargets(two, {{"msp-w10", compared(100.0, true)}}), way)["met"].is_null());
}

TEST_CASE("bench targets: mpp-w10 at rest with damping does not meet the undamped target") {
  const BenchDef def;
  CHECK(only(benchTargets(def, {{"mpp-w10", compared(1000.0, true)}}), "mpp-w10")["met"] == true);
  const json damped = only(benchTargets(def, {{"mpp-w10", compared(1000.0, true, 0.4)}}), "mpp-w10");
  CHECK(damped["met"] == false);
  CHECK(damped["figure"] == "1000.0 s at rest, with damping 0.4");
  CHECK(only(benchTargets(def, {{"mpp-w10", compared(1801.0, true)}}), "mpp-w10")["met"] == false);
}

TEST_CASE("bench targets: the rest series judges its largest point only at about 30,400 grains") {
  const BenchDef def;
  const json small = {{"rest",
                       {{{"n_grains", 2000}, {"equilibrium_reached", true}, {"wall_s", 300.0}},
                        {{"n_grains", 8000}, {"equilibrium_reached", false}, {"wall_s", 4000.0}}}},
                      {"rest_exponent", {{"wall", 1.5}}}};
  const json t = benchTargets(def, small);
  CHECK(only(t, "rest: 30,400")["met"].is_null());
  CHECK(only(t, "rest: 30,400")["figure"] == "8000 spheres: not at rest after 4000.0 s");
  CHECK(only(t, "rest: time")["figure"] == "k = 1.50");
  json large = small;
  large["rest"].push_back({{"n_grains", 30296}, {"equilibrium_reached", true}, {"wall_s", 1700.0}});
  CHECK(only(benchTargets(def, large), "rest: 30,400")["met"] == true);
}

TEST_CASE("bench targets: the scaling series meets the linear-cost target at exponent 1.1 or less") {
  const BenchDef def;
  CHECK(only(benchTargets(def, {{"scaling_exponent", {{"nscd", 1.05}}}}), "scaling")["met"] == true);
  CHECK(only(benchTargets(def, {{"scaling_exponent", {{"nscd", 1.35}}}}), "scaling")["met"] == false);
  CHECK(only(benchTargets(def, {{"scaling_exponent", {{"nscd", nullptr}}}}), "scaling")["met"].is_null());
}

namespace {

// One benchmark of Google Benchmark's JSON report, as `--micro-repetitions` writes it.
json solveRun(const std::string& preconditioner, double microseconds, double iterations, const std::string& aggregate) {
  json b = {{"run_name", "MprgpSolve/" + preconditioner + "/pile"},
            {"real_time", microseconds},
            {"time_unit", "us"},
            {"iterations_per_solve", iterations},
            {"rows", 4731.0}};
  b["run_type"] = aggregate.empty() ? "iteration" : "aggregate";
  if (!aggregate.empty()) b["aggregate_name"] = aggregate;
  return b;
}

}  // namespace

TEST_CASE("micro targets: the creep block is met by a preconditioner at least 5 times faster than sgs, by the median") {
  using confpack::bench::microTargets;
  // Today's figures on r0008's block (docs/performance.md): cholesky 630 ms against sgs's 54 ms.
  const json today =
      microTargets({{"benchmarks", {solveRun("sgs", 54e3, 661, ""), solveRun("cholesky", 630e3, 56, "")}}});
  REQUIRE(today.size() == 1);
  CHECK(today[0]["met"] == false);
  CHECK(today[0]["figure"].get<std::string>().rfind("cholesky 0.086 times sgs's speed", 0) == 0);
  // 5.4 times faster meets it; the medians decide, not the means.
  const json faster =
      microTargets({{"benchmarks",
                     {solveRun("sgs", 54e3, 661, "median"), solveRun("sgs", 1.0, 661, "mean"),
                      solveRun("cholesky", 10e3, 20, "median"), solveRun("cholesky", 1e9, 20, "mean")}}});
  CHECK(faster[0]["met"] == true);
  // 4.9 times does not.
  CHECK(microTargets(
            {{"benchmarks", {solveRun("sgs", 49e3, 661, ""), solveRun("cholesky", 10e3, 20, "")}}})[0]["met"] == false);
  // sgs alone: nothing to compare, the target shown but not judged; no pile solve: no target.
  CHECK(microTargets({{"benchmarks", {solveRun("sgs", 54e3, 661, "")}}})[0]["met"].is_null());
  CHECK(microTargets({{"benchmarks", json::array({{{"run_name", "MprgpSolve/sgs/spheres/2000"}}})}}).empty());
}
