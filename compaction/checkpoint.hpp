#pragma once
// A compaction's checkpoint (docs/model.md, "Checkpoints"): the state a compaction resumes from
// after it was stopped (a Slurm time limit, SIGTERM, a killed machine), written atomically to one
// JSON file. It holds the run's identity (its configuration, threads aside, and a fingerprint of
// its deposit), where the protocol stood (stage, step, simulated time, the adaptive step, the
// counters behind result.json's timing and history), the finisher's state and the backend's own
// (BackendState: poses, velocities and, for nscd, everything else its next step reads, so that an
// nscd run resumed from a checkpoint takes the same steps, bit for bit, as one never stopped).
#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "compaction/deposition.hpp"
#include "core/backend.hpp"
#include "core/run_config.hpp"

namespace confpack::compaction {

/// Where and how often a compaction saves its state. With a file that holds a checkpoint of the
/// same run, the compaction resumes from it; it writes the file at the first equilibrium check
/// after every `everySeconds` of wall time, and when SIGINT or SIGTERM stops it.
struct Checkpointing {
  std::filesystem::path file;  ///< empty: no checkpoint
  /// 5 min: at most that much work lost to a machine that dies, for a save of about 1 MB and
  /// 10 to 20 ms per 1,650 spheres (measured).
  double everySeconds = 300.0;
};

/// The state of a compaction at one equilibrium check.
struct CheckPoint {
  long steps = 0;
  double time = 0.0;           ///< simulated time [t0]
  double wallSeconds = 0.0;    ///< since the start of the compaction [s]
  double maxForceRatio = 0.0;  ///< equilibrium ratios at this check
  double maxMomentRatio = 0.0;
  double maxKineticRatio = 0.0;
  double interpenetrationPercent = 0.0;  ///< exact bulk interpenetration [%] (no lattice)
  long iterations = 0;                   ///< solver iterations (sweeps) since the start, summed over steps
  double rowUpdates = 0.0;               ///< contact rows x iterations since the start
  double solveSeconds = 0.0;             ///< time in the solve phase since the start [s]
  double stepSeconds = 0.0;              ///< time in the backend's steps since the start (no checks) [s]
  double stepCpuSeconds = 0.0;           ///< the same in process CPU time (all threads) [s]
  /// The pile's relaxation (docs/model.md, "Relaxation histories"): phi of the bulk region and Z of
  /// its force-carrying contacts per bulk grain at this check; NaN in a checkpoint written
  /// before they were recorded.
  double solidFraction = 0.0;
  double coordination = 0.0;
};

/// Where a compaction stands: its stage, clocks and counters (everything result.json's timing and
/// history are made of). Wall times count every attempt of a resumed run.
struct CompactionCounters {
  bool finisherStage = false;  ///< false: the dynamic steps (the fall); true: the finisher's
  long steps = 0;              ///< steps of both stages
  double simTime = 0.0;        ///< [t0]
  double dt = 0.0;             ///< the step last taken [t0]
  double dtLargest = 0.0;      ///< [t0]
  double lastCheckTime = 0.0;  ///< simulated time of the last check [t0]
  long iterations = 0;
  double rowUpdates = 0.0;
  double stepSeconds = 0.0;
  double stepCpuSeconds = 0.0;
  double elapsedSeconds = 0.0;  ///< wall time of the earlier attempts [s]
  std::array<double, static_cast<std::size_t>(core::Phase::Count)> phaseSeconds{};
  std::vector<CheckPoint> history;
  // How the fall ended (finisher stage only).
  std::string handOverAt;
  double handOverKineticRatio = 0.0;
  long dynamicSteps = 0;
  long dynamicIterations = 0;
  double dynamicWallSeconds = 0.0;
  int resumes = 0;  ///< times this run was resumed from a checkpoint
};

/// What a checkpoint must match to be resumed: the configuration (threads aside: they change no
/// bit of an nscd run) and the deposit's grains (count and a fingerprint of their poses and sizes).
nlohmann::json checkpointIdentity(const core::RunConfig& cfg, const Deposit& deposit);

struct LoadedCheckpoint {
  CompactionCounters counters;
  nlohmann::json backend;   ///< ContactBackend::saveState()
  nlohmann::json finisher;  ///< QuasiStaticFinisher::saveState() (finisher stage only)
};

/// The checkpoint in `file`, or nullopt when there is none, with `why` set when there was one that
/// cannot be resumed (another run's, another build's format, or unreadable).
std::optional<LoadedCheckpoint> readCheckpoint(const std::filesystem::path& file, const nlohmann::json& identity,
                                               std::string& why);

/// Where the checkpoint in `file` stands, for a sweep's status: "checkpoint: fall at t = 83.5,
/// 12 min" or "checkpoint: finisher step 140 (t = 83.5), 15 min", then how far from rest its last
/// measured check was: "; last check: force ratio 0.42 (rest below 0.0001), kinetic ratio 3e-05
/// (below 1e-08)"; empty when there is none or it cannot be read.
std::string describeCheckpoint(const std::filesystem::path& file);

/// Writes the checkpoint atomically (core::writeFileAtomically), creating its folder.
void writeCheckpoint(const std::filesystem::path& file, const nlohmann::json& identity,
                     const CompactionCounters& counters, const nlohmann::json& backend, const nlohmann::json& finisher);

}  // namespace confpack::compaction
