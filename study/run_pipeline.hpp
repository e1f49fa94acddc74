#pragma once
// One run of the protocol (docs/model.md, "Protocols"): deposit, compact with a backend until
// equilibrium or the time limit, analyse, write. The CLI's `run`, the sweeps and the benchmark all
// call this; none of them knows which backend runs.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "analysis/analyze.hpp"
#include "core/backend.hpp"
#include "core/deposition.hpp"
#include "core/packing.hpp"
#include "core/run_config.hpp"

namespace confpack::study {

/// Progress of a long run: fraction done in [0, 1] (of the time limit) and a short status line.
using RunProgressFn = std::function<void(double fraction, const std::string& status)>;

/// The fixed time step (docs/model.md, "Time step"): a grain should not move more than d_L/100 per
/// step with v_max = sqrt(2 g dh), dh the expected drop of the free surface:
///   dt = (1/100) sqrt(d_L / (2 dh)) sqrt(d_L / g).
/// dh = pile height - (grain volume / (L_x W phi_expected)), floored at one grain size.
double defaultTimeStep(const core::RunConfig& cfg, const core::Deposit& deposit);

/// Largest growth of the adaptive time step from one step to the next [-].
inline constexpr double kAdaptiveGrowth = 1.25;

/// An adaptive compaction also checks equilibrium whenever this much simulated time has passed
/// since its last check [t0]: its steps grow 50-fold and more, so that check_interval steps would
/// leave tens of t0 between checks. 0.5 t0 is about as often as the fixed step's default checks
/// (200 steps of 2.3e-3 t0 on msp-w10).
inline constexpr double kAdaptiveCheckSpacing = 0.5;

/// The step of an adaptive compaction (compaction.adaptive_dt). No grain should move more than
/// d_L/100 per step; the fixed step meets that at the worst speed of the compaction,
/// sqrt(2 g dh), which the pile reaches only while it falls. This step meets it at the speeds the
/// grains have now: the largest dt with v dt + g dt^2 / 2 <= s, where v is the fastest surface
/// point of any grain (|v| + |omega| r_bound) and s is a hundredth of the smallest grain's size
/// (d_L/100 for a monodisperse sample; smaller grains get a proportionally smaller bound, so that
/// nscd's alert distance, a fraction of the smaller grain of a pair, still covers an approach).
/// Clamped to [floor, kAdaptiveGrowth x previous]: never below the fixed step, and growing only
/// gradually, so that a grain set moving by a contact within a step is caught a step later.
/// The grains' radii and the bound s are fixed for a compaction: they are read once, here.
class AdaptiveTimeStep {
 public:
  AdaptiveTimeStep(const std::vector<core::Grain>& grains, double gravity, double floor);
  /// The step after one of length `previous`, from the grains' states now.
  double next(double previous, const std::vector<core::BodyState>& states) const;

 private:
  std::vector<double> radius_;  ///< bounding radius of each grain [d_L]
  double motion_ = 0.0;         ///< s: the largest motion per step [d_L]
  double gravity_ = 0.0;        ///< |g|
  double floor_ = 0.0;          ///< the fixed step [t0]
};

/// The state of a compaction at one equilibrium check.
struct CheckPoint {
  long steps = 0;
  double time = 0.0;              ///< simulated time [t0]
  double wallSeconds = 0.0;       ///< since the start of the compaction [s]
  double maxForceRatio = 0.0;     ///< equilibrium ratios at this check
  double maxMomentRatio = 0.0;
  double maxKineticRatio = 0.0;
  double interpenetrationPercent = 0.0;  ///< exact bulk interpenetration [%] (no lattice)
  long iterations = 0;            ///< solver iterations (sweeps) since the start, summed over steps
  double rowUpdates = 0.0;        ///< contact rows x iterations since the start
  double solveSeconds = 0.0;      ///< time in the solve phase since the start [s]
  double stepSeconds = 0.0;       ///< time in the backend's steps since the start (no checks) [s]
  double stepCpuSeconds = 0.0;    ///< the same in process CPU time (all threads) [s]
};

struct CompactionOutcome {
  core::Packing packing;                  ///< final poses with the last step's contacts and forces
  std::vector<core::BodyState> states;    ///< final velocities
  nlohmann::json equilibrium;             ///< result.json's equilibrium block
  nlohmann::json timing;                  ///< wall_s, steps, iterations, phases, ...
  nlohmann::json backendSettings;         ///< resolved backend settings
  std::vector<CheckPoint> history;        ///< one entry per equilibrium check
  double dt = 0.0;        ///< the fixed step, or the smallest (first) step of an adaptive run [t0]
  double dtLargest = 0.0; ///< the largest step taken [t0] (dt unless adaptive)
  /// The protocol that ran: the configured one, except that a backend without a finisher
  /// (Bullet) always runs the dynamic protocol.
  core::Protocol protocol = core::Protocol::Dynamic;
  bool reached = false;
};

/// The grains of a packing as the starting state of a compaction (`confpack run --from`): its
/// poses, at rest. pileHeight is the top of the highest grain's bounding sphere; there are no
/// placeholders. Throws std::invalid_argument if the packing has no grains.
core::Deposit depositFromPacking(const core::Packing& packing, const std::filesystem::path& source);

/// Compacts a deposit with cfg.backend. Writes ParaView frames into `vtkDir` when it is not empty.
CompactionOutcome compact(const core::RunConfig& cfg, const core::Deposit& deposit,
                          const std::filesystem::path& vtkDir = {}, const RunProgressFn& progress = {});

/// Analysis options of a run: the defaults, without analysis's own zero-velocity equilibrium
/// block (the pipeline writes the real one, with velocities).
analysis::AnalysisOptions analysisOptions();

/// Refuses (std::invalid_argument), before any work, a run whose analysis would visit more than
/// the analysis's max_cells cells (analysis::checkCells) with `grains` grains in cfg's box: `run`
/// and `sweep` call it with the configuration's estimated grain count, so that an oversized run
/// fails before its deposit and compaction rather than after them.
void checkRunCells(const core::RunConfig& cfg, double grains);

/// The result.json of a run (docs/model.md, "Results"): the measurements of the final packing, the
/// equilibrium block, timing, backend, seed and the resolved configuration.
nlohmann::json makeResult(const core::RunConfig& cfg, const core::Deposit& deposit, const CompactionOutcome& out,
                          const analysis::Analysis& measured);

/// A run done in memory: the final packing, its measurements and result.json's content.
struct FinishedRun {
  core::Packing packing;       ///< final poses with the last step's contacts and forces
  analysis::Analysis measured; ///< its measurements (the profiles come from here)
  nlohmann::json result;       ///< result.json (makeResult)
};

/// Deposit (unless `shared` is given) + compact + analyse, writing nothing but the ParaView frames
/// into `vtkDir` when it is not empty. runAndWrite and the Python module's run call it.
FinishedRun runProtocol(const core::RunConfig& cfg, const std::filesystem::path& vtkDir = {},
                        const RunProgressFn& progress = {}, const core::Deposit* shared = nullptr);

/// Deposit (unless `shared` is given: sweeps compact one deposit with both backends) + compact +
/// analyse, writing into `outDir` (which must exist): result.json, packing.json (final, with
/// contacts), profiles (*.csv), vtk/. Files are written atomically; result.json last, so its
/// presence means the run finished.
nlohmann::json runAndWrite(const core::RunConfig& cfg, const std::filesystem::path& outDir,
                           const RunProgressFn& progress = {}, const core::Deposit* shared = nullptr);

}  // namespace confpack::study
