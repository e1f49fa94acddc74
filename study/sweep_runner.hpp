#pragma once
// The real physics behind a sweep: compaction::deposit for the deposits and runAndWrite (deposit given,
// compact, analyse, write) for the runs. Kept apart from the sweep engine so that the engine and
// its tests do not depend on the backends.
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
SweepRunFn pipelineRunner(int threads = 0, double checkpointEvery = compaction::Checkpointing{}.everySeconds,
                          const std::string& settleWith = {});

/// Makes a run's deposit with compaction::deposit (box, population, deposition settings and seed).
SweepDepositFn pipelineDepositor();

}  // namespace confpack::study
