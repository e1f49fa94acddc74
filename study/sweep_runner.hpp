#pragma once
// The real physics behind a sweep: core::deposit for the deposits and runAndWrite (deposit given,
// compact, analyse, write) for the runs. Kept apart from the sweep engine so that the engine and
// its tests do not depend on the backends.
#include "study/checkpoint.hpp"
#include "study/sweep.hpp"

namespace confpack::study {

/// Runs one sweep run with runAndWrite on the shared deposit. `threads` > 0 overrides the run's
/// thread count at run time (it is not part of the run's identity in the table). Each run saves
/// its state in SWEEPDIR/checkpoints/rNNNN.json every `checkpointEvery` seconds and when it is
/// stopped, and a new attempt resumes from there (study/checkpoint.hpp); the file goes once the
/// run is done.
SweepRunFn pipelineRunner(int threads = 0, double checkpointEvery = Checkpointing{}.everySeconds);

/// Makes a run's deposit with core::deposit (box, population, deposition settings and seed).
SweepDepositFn pipelineDepositor();

}  // namespace confpack::study
