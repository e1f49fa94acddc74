#pragma once
// `confpack-bench --micro`: Google Benchmark micro-benchmarks of the hot phases of the nscd
// backend (issue 7), run in-process. Rates are items_per_second, with one item being:
//   BroadPhase/spheres/N        a grain (BroadPhase::findPairs over the N grains of a geometric
//                               deposit, biperiodic box of height 16 sized for N)
//   BroadPhase/pile/N           a grain, on the settled pile of the solver benchmarks below
//   NarrowPhase/<a>-<b>[-face]  a touching pair (NarrowPhase::collidePair, or collideWalls in a
//                               box whose only wall is the floor), gaps within the alert distance
//   GaussSeidelSweep/spheres/N  a contact row (one sweep of ContactSolver::solve over the rows
//                               of a pile that the nscd backend has settled briefly): "contact
//                               updates per second", the issue's target being 3e7 per core.
//   MprgpIteration/spheres/N    a contact row in one MPRGP iteration (cold solves of 50
//                               iterations on the same rows; an iteration is about two sweeps
//                               of work), the default solver since Gauss-Seidel cannot reach
//                               the equilibrium test's force balance.
//   MprgpSolve/<p>/spheres/N    a whole cold MPRGP solve to 1e-10 on the same rows, preconditioned
//                               by "sgs" or "cholesky" (N = 2,000 and 8,000), with its iterations
//                               and, for "cholesky", its factorisations and factor updates.
//   MprgpSolve/<p>/pile         the same on the pile of --micro-pile PACKING (rows: counter)
// The fixtures (deposits, poses, contact networks) are built once per process, outside the
// timed loops, and only for the benchmarks that the filter selects.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace confpack::bench {

struct MicroBenchDef {
  std::string filter = ".";  ///< regex over benchmark names (Google Benchmark's --benchmark_filter; a
                             ///< leading '-' negates it)
  int repetitions = 5;       ///< repetitions of each benchmark [-], >= 1; with more than one only the
                             ///< aggregates (mean, median, stddev, cv) are reported
  double minTime = 0.3;      ///< minimum timed duration of one repetition [s], > 0 (Google Benchmark's
                             ///< default is 0.5; 0.3 keeps the default run near a minute)
  std::uint64_t seed = 1;    ///< seed of the deposits and of the random poses
  /// A packing file (--micro-pile, e.g. of a run stopped in its creep): MprgpSolve/<p>/pile then
  /// times a solve of its step after kPileSteps from rest; empty: none.
  std::filesystem::path pile;
};

/// Writes the contact problem of a packing's step (the pile of --micro-pile after kPileSteps from
/// rest, cold, frictionless walls) and its MPRGP solution to 1e-10 into the new folder `dir`, for
/// solvers outside confpack to be tried on the same block (bench/free_block.py):
///   rows.csv    one frictionless row a line, in sweep order: bodies a and b (the last body index
///               is the static walls), n, l_a x n, l_b x n, the bias c [d_L/t0] and the solved
///               impulse r [m_L d_L/t0]; u_n = n.(v_b - v_a) + (l_b x n).w_b - (l_a x n).w_a
///   bodies.csv  one body a line: 1/m, the world-frame inverse inertia (row-major), the free
///               velocities v and w of the step, the centre at q_m (the walls' line: zeros)
///   block.json  the step dt, the iterations and the residual of the solve, rows and bodies
/// Throws std::invalid_argument if `dir` exists or the pile has friction rows; std::runtime_error
/// if the packing cannot be read or the folder written (nothing is left at `dir` then).
void dumpPileBlock(const std::filesystem::path& pile, const std::filesystem::path& dir);

/// Throws std::invalid_argument if `dir` exists or `pile` is not a file: dumpPileBlock's refusals
/// before any work.
void validatePileDump(const std::filesystem::path& pile, const std::filesystem::path& dir);

/// Names of every micro-benchmark, in run order (without the --micro-pile ones).
const std::vector<std::string>& microBenchNames();

/// Throws std::invalid_argument if a field is out of range, the filter is not a valid (POSIX
/// extended) regex, or it selects no benchmark.
void validateMicroBench(const MicroBenchDef& def);

/// The creep-block target of the multilevel contact solve (docs/performance.md, "Where the speed
/// targets stand"): a `--micro-pile` step solved to 1e-10 at least 5 times faster than by
/// SGS-preconditioned MPRGP. From Google Benchmark's JSON report: the fastest other
/// MprgpSolve/<p>/pile against MprgpSolve/sgs/pile, each by its median wall time a solve (or its
/// one run without repetitions). An array of {"target", "figure", "met"}: empty without the pile's
/// sgs solve, "met" null when no other preconditioner ran beside it.
nlohmann::json microTargets(const nlohmann::json& report);

/// Runs the selected benchmarks, prints Google Benchmark's console table on stdout and writes its
/// JSON report, with microTargets' "targets", to `out` atomically (a temporary file next to it,
/// then a rename); returns the targets. Throws std::runtime_error, leaving nothing at `out`, if a
/// fixture cannot be built or a run fails. Google Benchmark keeps global state: call at most once
/// per process.
nlohmann::json runMicroBench(const MicroBenchDef& def, const std::filesystem::path& out);

}  // namespace confpack::bench
