#include "study/sweep_runner.hpp"

#include "core/deposition.hpp"
#include "study/run_pipeline.hpp"

namespace confpack::study {

SweepRunFn pipelineRunner(int threads) {
  return [threads](const core::RunConfig& cfg, const std::filesystem::path& runDir, const core::Deposit& deposit,
                   const RunProgressFn& progress) {
    core::RunConfig c = cfg;
    if (threads > 0) c.threads = threads;
    return runAndWrite(c, runDir, progress, &deposit);
  };
}

SweepDepositFn pipelineDepositor() {
  return [](const core::RunConfig& cfg) { return core::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed); };
}

}  // namespace confpack::study
