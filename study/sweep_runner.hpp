#pragma once
// The real physics behind a sweep: compaction::deposit for the deposits and runAndWrite (deposit given,
// compact, analyse, write) for the runs. Kept apart from the sweep engine so that the engine and
// its tests do not depend on the backends.
#include <filesystem>
#include <functional>
#include <string>

#include "compaction/checkpoint.hpp"
#include "study/sweep.hpp"

namespace confpack::study {

/// Runs one sweep run with runAndWrite on the shared deposit. `threads` > 0 overrides the run's
/// thread count at run time (it is not part of the run's identity in the table). Each run saves
/// its state in SWEEPDIR/checkpoints/rNNNN.json every `checkpointEvery` seconds and when it is
/// stopped, and a new attempt resumes from there (compaction/checkpoint.hpp); the file goes once the
/// run is done. With `settleWith` (a sweep's settle_with), a run of another backend is then taken
/// on to rest by that one into RUN/settled/ (settleAndWrite; its checkpoint rNNNN-settled.json).
/// Until that settle is done, the run's own finished folder is kept in
/// SWEEPDIR/checkpoints/rNNNN-unsettled/, so that a settle stopped part-way resumes without running
/// the first backend again (runOrRestore).
SweepRunFn pipelineRunner(int threads = 0, double checkpointEvery = compaction::Checkpointing{}.everySeconds,
                          const std::string& settleWith = {});

/// The first stage of a run with a settle: when keptDir holds a finished run folder whose
/// config.json is runDir's (the same JSON), copies it into runDir and returns its result.json;
/// otherwise calls `run` (which fills runDir) and then keeps a copy of runDir in keptDir, renamed
/// into place whole. Whoever finishes the settle removes keptDir.
nlohmann::json runOrRestore(const std::filesystem::path& runDir, const std::filesystem::path& keptDir,
                            const std::function<nlohmann::json()>& run);

/// Makes a run's deposit with compaction::deposit (box, population, deposition settings and seed).
SweepDepositFn pipelineDepositor();

}  // namespace confpack::study
