// benchTargets (bench/bench.hpp): each speed target judged from the figures of a bench run, and
// left undecided where the run was not at the target's size.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "bench/bench.hpp"

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
