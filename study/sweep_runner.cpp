#include "study/sweep_runner.hpp"

#include "compaction/deposition.hpp"
#include "core/json_input.hpp"
#include "study/run_pipeline.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

nlohmann::json runOrRestore(const fs::path& runDir, const fs::path& keptDir,
                            const std::function<nlohmann::json()>& run) {
  const fs::path config = runDir / "config.json";
  if (fs::exists(keptDir / "result.json") && fs::exists(keptDir / "config.json") &&
      core::readJsonFile(keptDir / "config.json", "config") == core::readJsonFile(config, "config")) {
    fs::copy(keptDir, runDir, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    return core::readJsonFile(runDir / "result.json", "result");
  }
  fs::remove_all(keptDir);  // another configuration's, or a copy cut short
  nlohmann::json result = run();
  // Copied under another name, then renamed: a folder under keptDir's name is always whole.
  const fs::path partial = keptDir.string() + ".partial";
  fs::remove_all(partial);
  fs::create_directories(partial.parent_path());
  fs::copy(runDir, partial, fs::copy_options::recursive);
  fs::rename(partial, keptDir);
  return result;
}

SweepRunFn pipelineRunner(int threads, double checkpointEvery, const std::string& settleWith) {
  return [threads, checkpointEvery, settleWith](const core::RunConfig& cfg, const fs::path& runDir,
                                                const compaction::Deposit& deposit, const RunProgressFn& progress) {
    core::RunConfig c = cfg;
    if (threads > 0) c.threads = threads;
    // runDir is SWEEPDIR/runs/rNNNN.
    const fs::path sweepDir = runDir.parent_path().parent_path();
    const std::string name = runDir.filename().string();
    compaction::Checkpointing checkpointing;
    checkpointing.everySeconds = checkpointEvery;
    checkpointing.file = sweepCheckpointFile(sweepDir, name);
    const auto run = [&] { return runAndWrite(c, runDir, progress, &deposit, checkpointing); };
    if (settleWith.empty() || c.backend == settleWith) return run();

    const fs::path kept = sweepKeptRunFolder(sweepDir, name);
    nlohmann::json result = runOrRestore(runDir, kept, run);
    checkpointing.file = sweepSettleCheckpointFile(sweepDir, name);
    settleAndWrite(c, runDir, settleWith, progress, checkpointing);
    fs::remove_all(kept);
    return result;
  };
}

SweepDepositFn pipelineDepositor() {
  return
      [](const core::RunConfig& cfg) { return compaction::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed); };
}

}  // namespace confpack::study
