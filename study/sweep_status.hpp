#pragma once
// Where each run of a sweep folder stands, for `confpack sweep DIR --status` and for choosing what a
// new job array submits: from the run's markers, its claim (study/run_claim.hpp) and the Slurm
// job last handed it (study/slurm.hpp).
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "study/run_claim.hpp"
#include "study/slurm.hpp"
#include "study/sweep.hpp"

namespace confpack::study {

enum class RunState {
  Done,     ///< done.json
  Running,  ///< claimed by a live (or uncheckable) holder
  Queued,   ///< handed to an array task that Slurm still lists, not yet started on it
  Failed,   ///< failed.json, or its task ended without finishing it
  Missing   ///< never run, or interrupted and not handed to a live task
};
std::string_view toString(RunState s);

/// What is known of one run, gathered from the folder and from Slurm.
struct RunFacts {
  RunStatus markers = RunStatus::Pending;    ///< runStatus() of its folder
  std::string failedError;                   ///< failed.json's "error"
  std::string failedAt;                      ///< failed.json's "finished" (UTC, ISO 8601)
  std::optional<ClaimHolder> claim;          ///< its claim, if any
  Liveness claimHolder = Liveness::Unknown;  ///< of the claim's holder
  std::string task;                          ///< the array task last handed it ("JOB_TASK"); empty: never submitted
  std::string taskSubmitted;                 ///< when that task's array was submitted (UTC, ISO 8601)
  std::optional<std::string>
      taskState;            ///< that task's Slurm state ("" ended and forgotten); nothing: squeue did not answer
  std::string taskLogLine;  ///< the last line of that task's log
  std::string checkpoint;   ///< where its checkpoint stands (describeCheckpoint); empty: none
};

struct RunReport {
  RunState state = RunState::Missing;
  std::string job;     ///< the Slurm job working on it, queued with it, or that last failed it
  std::string detail;  ///< why it failed; who holds it
};

/// The state of a run from its facts, in this order: done.json; a claim whose holder is not dead
/// (running); failed.json (failed, its error) unless a live task was submitted for it after it
/// failed (queued); a task Slurm lists as live (queued); a dead claim or an ended task (failed,
/// the last line of the task's log); otherwise missing. A run that is not done says where its
/// checkpoint stands, the point a new attempt resumes from.
RunReport classifyRun(const RunFacts& facts);

/// How the status asks Slurm about a job (slurmJobState; a test passes its own).
using JobStateFn = std::function<std::optional<std::string>(const std::string& job)>;

/// Every run's report, in table order. Slurm is asked once per array task.
std::vector<RunReport> sweepStatus(const std::filesystem::path& dir, const std::vector<SweepRun>& runs,
                                   const LivenessFn& alive = holderLiveness,
                                   const JobStateFn& jobState = slurmJobState);

/// The runs a new submission takes: those failed or missing (not done, running or queued), by index.
std::vector<std::size_t> unfinishedRuns(const std::vector<RunReport>& reports);

/// The status as text: one line per run (name, state, job, label, detail), then the counts.
std::string formatStatus(const std::vector<SweepRun>& runs, const std::vector<RunReport>& reports);

}  // namespace confpack::study
