#pragma once
// The compaction of a deposit under gravity to static equilibrium (docs/model.md, "Protocols"),
// with either backend: the fall (time steps until equilibrium, the time limit or, quasi-static
// protocol, the end of the fall), the hand-over, the quasi-static finisher (nscd), with
// equilibrium checks, checkpoints and ParaView frames along the way. `run`, the sweeps, the
// benchmark and Python all compact through compact().
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "compaction/checkpoint.hpp"
#include "compaction/deposition.hpp"
#include "core/backend.hpp"
#include "core/packing.hpp"
#include "core/run_config.hpp"

namespace confpack::compaction {

/// Progress of a long compaction: fraction done in [0, 1] (of the time limit, or of the
/// finisher's step budget) and a short status line.
using CompactionProgressFn = std::function<void(double fraction, const std::string& status)>;

struct CompactionOutcome {
  core::Packing packing;                ///< final poses with the last step's contacts and forces
  std::vector<core::BodyState> states;  ///< final velocities
  nlohmann::json equilibrium;           ///< result.json's equilibrium block
  nlohmann::json timing;                ///< wall_s, steps, iterations, phases, ...
  nlohmann::json backendSettings;       ///< resolved backend settings
  std::vector<CheckPoint> history;      ///< one entry per equilibrium check
  double dt = 0.0;                      ///< the fixed step, or the smallest (first) step of an adaptive run [t0]
  double dtLargest = 0.0;               ///< the largest step taken [t0] (dt unless adaptive)
  /// The protocol that ran: the configured one, except that a backend without a finisher
  /// (Bullet) always runs the dynamic protocol.
  core::Protocol protocol = core::Protocol::Dynamic;
  bool reached = false;
};

/// The grains of a packing as the starting state of a compaction (`confpack run --from`): its
/// poses, at rest. pileHeight is the top of the highest grain's bounding sphere; there are no
/// placeholders. Throws std::invalid_argument if the packing has no grains.
Deposit depositFromPacking(const core::Packing& packing, const std::filesystem::path& source);

/// Compacts a deposit with cfg.backend. Writes ParaView frames into `vtkDir` when it is not empty.
/// With a checkpoint file (compaction/checkpoint.hpp) it resumes from the file when that holds a
/// checkpoint of this run, and saves its state there as it goes; result.json's timing then says
/// how often the run was resumed. A resumed run's ParaView series starts with the deposit and
/// goes on from the resume.
CompactionOutcome compact(const core::RunConfig& cfg, const Deposit& deposit, const std::filesystem::path& vtkDir = {},
                          const CompactionProgressFn& progress = {}, const Checkpointing& checkpointing = {});

}  // namespace confpack::compaction
