#pragma once
// One run of the protocol (docs/model.md, "Protocols"): deposit, compact with a backend until
// equilibrium or the time limit (compaction/), analyse, write. The CLI's `run`, the sweeps and the benchmark all
// call this; none of them knows which backend runs.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "analysis/analyze.hpp"
#include "compaction/checkpoint.hpp"
#include "compaction/compaction.hpp"
#include "compaction/deposition.hpp"
#include "core/packing.hpp"
#include "core/run_config.hpp"

namespace confpack::study {

/// Progress of a long run: the compaction's (fraction of its time limit or step budget, status).
using RunProgressFn = compaction::CompactionProgressFn;

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
nlohmann::json makeResult(const core::RunConfig& cfg, const compaction::Deposit& deposit,
                          const compaction::CompactionOutcome& out, const analysis::Analysis& measured);

/// result.json's settle block of a run from a packing (`run --from`, docs/model.md, "Settling a
/// pile from another backend"): how far its grains moved to reach rest (largest and mean centre
/// displacement [d_L]), in how many steps, and phi of the bulk and Z by type of the packing as it
/// came (`before`, with the forces of the backend that made it: `from`'s contacts) and as it ended
/// (`after`), measured as the analysis measures them.
nlohmann::json settleRecord(const core::RunConfig& cfg, const compaction::Deposit& from,
                            const compaction::CompactionOutcome& out);

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
  core::Packing packing;        ///< final poses with the last step's contacts and forces
  analysis::Analysis measured;  ///< its measurements (the profiles come from here)
  nlohmann::json result;        ///< result.json (makeResult)
};

/// Deposit (unless `shared` is given) + compact + analyse, writing nothing but the ParaView frames
/// into `vtkDir` when it is not empty. runAndWrite and the Python module's run call it.
FinishedRun runProtocol(const core::RunConfig& cfg, const std::filesystem::path& vtkDir = {},
                        const RunProgressFn& progress = {}, const compaction::Deposit* shared = nullptr,
                        const compaction::Checkpointing& checkpointing = {});

/// Deposit (unless `shared` is given: sweeps compact one deposit with both backends) + compact +
/// analyse, writing into `outDir` (which must exist): result.json, packing.json (final, with
/// contacts), profiles (*.csv), vtk/. Files are written atomically; result.json last, so its
/// presence means the run finished; then the checkpoint file, if any, is removed.
nlohmann::json runAndWrite(const core::RunConfig& cfg, const std::filesystem::path& outDir,
                           const RunProgressFn& progress = {}, const compaction::Deposit* shared = nullptr,
                           const compaction::Checkpointing& checkpointing = {});

/// Where a run's settle keeps its result: RUN/settled/ (config.json, result.json, packing.json,
/// profiles, vtk/).
inline constexpr const char* kSettledFolder = "settled";

/// The configuration of a run's settle: the run's, with `backend`, that backend's default options
/// and the quasi-static protocol (docs/model.md, "Settling a pile from another backend").
core::RunConfig settleConfig(const core::RunConfig& cfg, const std::string& backend);

/// Takes the final packing of the run in `runDir` (runDir/packing.json, as runAndWrite left it) on
/// to rest with `backend` (settleConfig) and writes that run into runDir/settled/ as runAndWrite
/// does, with its config.json; its result.json's settle block says what it did, `from` naming
/// ../packing.json. Returns that result.json.
nlohmann::json settleAndWrite(const core::RunConfig& cfg, const std::filesystem::path& runDir,
                              const std::string& backend, const RunProgressFn& progress = {},
                              const compaction::Checkpointing& checkpointing = {});

}  // namespace confpack::study
