#include "study/sweep_runner.hpp"

#include "compaction/deposition.hpp"
#include "study/run_pipeline.hpp"

namespace confpack::study {

SweepRunFn pipelineRunner(int threads, double checkpointEvery, const std::string& settleWith) {
  return [threads, checkpointEvery, settleWith](const core::RunConfig& cfg, const std::filesystem::path& runDir,
                                                const compaction::Deposit& deposit, const RunProgressFn& progress) {
    core::RunConfig c = cfg;
    if (threads > 0) c.threads = threads;
    // runDir is SWEEPDIR/runs/rNNNN.
    const std::filesystem::path sweepDir = runDir.parent_path().parent_path();
    const std::string name = runDir.filename().string();
    compaction::Checkpointing checkpointing;
    checkpointing.everySeconds = checkpointEvery;
    checkpointing.file = sweepCheckpointFile(sweepDir, name);
    nlohmann::json result = runAndWrite(c, runDir, progress, &deposit, checkpointing);
    if (!settleWith.empty() && c.backend != settleWith) {
      checkpointing.file = sweepCheckpointFile(sweepDir, name + "-settled");
      settleAndWrite(c, runDir, settleWith, progress, checkpointing);
    }
    return result;
  };
}

SweepDepositFn pipelineDepositor() {
  return
      [](const core::RunConfig& cfg) { return compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed); };
}

}  // namespace confpack::study
