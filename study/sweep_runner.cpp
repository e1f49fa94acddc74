#include "study/sweep_runner.hpp"

#include "core/deposition.hpp"
#include "study/run_pipeline.hpp"

namespace confpack::study {

SweepRunFn pipelineRunner(int threads, double checkpointEvery) {
  return [threads, checkpointEvery](const core::RunConfig& cfg, const std::filesystem::path& runDir,
                                    const core::Deposit& deposit, const RunProgressFn& progress) {
    core::RunConfig c = cfg;
    if (threads > 0) c.threads = threads;
    // runDir is SWEEPDIR/runs/rNNNN.
    Checkpointing checkpointing;
    checkpointing.everySeconds = checkpointEvery;
    checkpointing.file = sweepCheckpointFile(runDir.parent_path().parent_path(), runDir.filename().string());
    return runAndWrite(c, runDir, progress, &deposit, checkpointing);
  };
}

SweepDepositFn pipelineDepositor() {
  return [](const core::RunConfig& cfg) { return core::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed); };
}

}  // namespace confpack::study
