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
#include "study/checkpoint.hpp"

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
/// grains have now: the largest dt with v dt + g dt^2 / 2 <= s, where v is the fastest motion of
/// any grain's boundary (|v| + |omega| r_bound; |v| for a sphere, whose spin leaves its boundary
/// in place) and s is a hundredth of the smallest grain's size
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
  std::vector<double> spinLever_;  ///< Grain::spinLever of each grain [d_L]
  double motion_ = 0.0;         ///< s: the largest motion per step [d_L]
  double gravity_ = 0.0;        ///< |g|
  double floor_ = 0.0;          ///< the fixed step [t0]
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
/// With a checkpoint file (study/checkpoint.hpp) it resumes from the file when that holds a
/// checkpoint of this run, and saves its state there as it goes; result.json's timing then says
/// how often the run was resumed. A resumed run's ParaView series starts with the deposit and
/// goes on from the resume.
CompactionOutcome compact(const core::RunConfig& cfg, const core::Deposit& deposit,
                          const std::filesystem::path& vtkDir = {}, const RunProgressFn& progress = {},
                          const Checkpointing& checkpointing = {});

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

/// A run's result.json before and after reanalyseRun.
struct Reanalysed {
  nlohmann::json before;
  nlohmann::json after;
};

/// Measures a finished run's final packing again (`confpack sweep --reanalyse`), so that a study
/// compacted over several versions is reported with one analysis: reads runDir/packing.json,
/// analyses it, rewrites the profiles and then result.json, atomically each. result.json's
/// measurements are replaced (a block this analysis no longer writes is dropped); what the
/// compaction wrote beside them (backend, seed, n_grains, equilibrium, timing, deposit, config,
/// confpack_version) is kept. Throws std::invalid_argument naming the file when packing.json or
/// result.json cannot be read, before anything is written.
Reanalysed reanalyseRun(const std::filesystem::path& runDir);

/// A run done in memory: the final packing, its measurements and result.json's content.
struct FinishedRun {
  core::Packing packing;       ///< final poses with the last step's contacts and forces
  analysis::Analysis measured; ///< its measurements (the profiles come from here)
  nlohmann::json result;       ///< result.json (makeResult)
};

/// Deposit (unless `shared` is given) + compact + analyse, writing nothing but the ParaView frames
/// into `vtkDir` when it is not empty. runAndWrite and the Python module's run call it.
FinishedRun runProtocol(const core::RunConfig& cfg, const std::filesystem::path& vtkDir = {},
                        const RunProgressFn& progress = {}, const core::Deposit* shared = nullptr,
                        const Checkpointing& checkpointing = {});

/// Deposit (unless `shared` is given: sweeps compact one deposit with both backends) + compact +
/// analyse, writing into `outDir` (which must exist): result.json, packing.json (final, with
/// contacts), profiles (*.csv), vtk/. Files are written atomically; result.json last, so its
/// presence means the run finished; then the checkpoint file, if any, is removed.
nlohmann::json runAndWrite(const core::RunConfig& cfg, const std::filesystem::path& outDir,
                           const RunProgressFn& progress = {}, const core::Deposit* shared = nullptr,
                           const Checkpointing& checkpointing = {});

}  // namespace confpack::study
