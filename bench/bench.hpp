#pragma once
// `confpack-bench`: the two backends on the same deposits, in one process.
//
// Cases:
//   msp-w10  monodisperse spheres, L_x = 20, W = 10, h = 16 (about 3,700 grains at phi 0.6)
//   mpp-w10  monodisperse pinacoids, same box
//   scaling  spheres from about 2,000 to 30,400 grains (W = 10, h = 16, the periodic length
//            stretched): cost per step over a fixed number of steps once the pile has fallen
//            for a while and carries its weight, fitted as t_step ~ n^k
// For each backend: wall time to equilibrium (or to the time limit), final interpenetration and
// equilibrium ratios, steps, sweeps per step, time per step and per phase, contact updates per
// second, peak memory; and nscd/bullet ratios. Bullet is also credited with the first check at
// which its interpenetration was at or below nscd's final value.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "study/run_pipeline.hpp"

namespace confpack::bench {

struct BenchDef {
  /// Which cases to run: msp-w10, mpp-w10, scaling (cost of a step against n) and rest (time to
  /// equilibrium against n; not among the defaults, being hours long at its default sizes).
  std::vector<std::string> cases = {"msp-w10", "mpp-w10", "scaling"};
  double timeLimit = 200.0;  ///< simulated time limit of a compaction [t0]
  double scale = 1.0;        ///< multiplies the box length and width (smaller = quicker) [-]
  int scalingSteps = 200;    ///< steps timed per scaling point [-]
  double scalingFall = 4.0;  ///< simulated time before the timed steps of a scaling point [t0]
  std::vector<int> scalingSizes = {2000, 4000, 8000, 16000, 30400};  ///< grains per scaling point
  /// Grains per point of the rest series: nscd compactions to equilibrium in the scaling series'
  /// box (W = 10, h = 16, L_x stretched), with `protocol` and `adaptiveDt`.
  std::vector<int> restSizes = {2000, 8000, 30400};
  std::uint64_t seed = 1;
  int threads = 1;
  /// Both backends of msp-w10 and mpp-w10, and the rest series, on the adaptive time step (compaction.adaptive_dt);
  /// the scaling series always takes fixed steps (it times a step, not a compaction).
  bool adaptiveDt = false;
  /// The protocol of msp-w10, mpp-w10 and the rest series (docs/model.md); Bullet runs dynamic either way.
  core::Protocol protocol = core::Protocol::Dynamic;
};

/// Names accepted in BenchDef::cases.
const std::vector<std::string>& benchCaseNames();

/// The speed targets the cases measure (docs/performance.md, "Where the speed targets
/// stand"), each with the figure this bench run reached: an array of {"target", "figure", "met"},
/// "met" null where the case did not run at the target's size (another --scale, --threads or
/// rest size) and the figure cannot say. From `cases`, runBench's "cases" object.
///   msp-w10  nscd at equilibrium in at most 60 s on one thread (scale 1), and the step on the way,
///            at most 180 s
///   mpp-w10  nscd at equilibrium without damping in at most 30 minutes (scale 1)
///   rest     30,400 spheres at equilibrium in at most 30 minutes (its point of about 30,400 grains)
///   scaling  nscd's cost per step linear in n: fitted exponent at most 1.1
nlohmann::json benchTargets(const BenchDef& def, const nlohmann::json& cases);

/// One target as a line: "statement: figure (met)", "(not met)" or "(not judged by this run)".
std::string targetLine(const nlohmann::json& target);

/// Runs the benchmark and returns bench.json (shape documented in the README). `log` gets one line
/// per case and per finished compaction; `progress` the progress of each compaction, its status
/// led by the case ("msp-w10 nscd t=12.0 step ...").
nlohmann::json runBench(const BenchDef& def, const std::function<void(const std::string&)>& log = {},
                        const study::RunProgressFn& progress = {});

}  // namespace confpack::bench
