#pragma once
// A sweep as a Slurm job array (docs/cluster.md): the batch script over the runs that are still
// unfinished, its submission through sbatch, and what Slurm says of a job (squeue). Each array
// task runs `confpack sweep SWEEPDIR --runs LIST`, one run a task by default, so that the study
// takes as long as its slowest run; each run reads its deposit or makes it (the same bytes).
//
// SWEEPDIR/slurm/study.sbatch        the last script written
// SWEEPDIR/slurm/submitted.json      every submission: the job id and the runs of each task
// SWEEPDIR/slurm/logs/JOB_TASK.out   each task's stdout and stderr
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "study/sweep.hpp"

namespace confpack::study {

/// What `confpack sweep --slurm` puts in the script's #SBATCH lines. Empty strings are left out
/// (the cluster's defaults apply).
struct SlurmOptions {
  std::string partition;                ///< --partition
  std::string time;                     ///< --time, Slurm's forms: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS
  std::string mem;                      ///< --mem, an integer with an optional unit K, M, G or T (default M)
  std::string account;                  ///< --account
  int cpusPerTask = 1;                  ///< --cpus-per-task; also the runs a task runs at once (--jobs)
  int arrayLimit = 0;                   ///< tasks running at once (--array=0-N%LIMIT); 0 = no limit
  std::size_t maxTasks = 0;             ///< at most this many array tasks (runs dealt round-robin); 0 = one per run
  std::vector<std::string> extraLines;  ///< more #SBATCH options, each "--option[=value]"
};

/// Refuses a bad value with std::invalid_argument naming its option ("--time: ...").
void checkSlurmOptions(const SlurmOptions& opt);

/// Refuses a sweep folder whose absolute path cannot be written into an #SBATCH line (white
/// space, quotes, '%', '\\').
void checkSlurmPath(const std::filesystem::path& sweepDir);

/// The runs of one array task, by name, in table order.
struct ArrayTask {
  std::vector<std::string> runs;
};

/// Deals `todo` (indices into `runs`) into array tasks: one run per task, or with maxTasks > 0
/// and fewer tasks than runs, the j-th run of `todo` in table order to task j mod maxTasks; each
/// task's runs in table order. With `partners` (equalTimePartners, a sweep's equal_time), a run
/// goes into its partner's task, which runs the partner first: the unit dealt is a partner and the
/// runs that take their time from it.
std::vector<ArrayTask> planArrayTasks(const std::vector<SweepRun>& runs, const std::vector<std::size_t>& todo,
                                      std::size_t maxTasks = 0,
                                      const std::vector<std::optional<std::size_t>>& partners = {});

/// The batch script: #SBATCH lines (job name, the array, logs under SWEEPDIR/slurm/logs, the
/// options), then each task's run list and the call of `confpack` (absolute path) on SWEEPDIR.
std::string sbatchScript(const SlurmOptions& opt, const std::vector<ArrayTask>& tasks,
                         const std::filesystem::path& confpack, const std::filesystem::path& sweepDir,
                         std::string_view sweepName);

/// The job id of `sbatch --parsable` ("1234" or "1234;cluster"); std::runtime_error otherwise.
std::string jobIdFromSbatch(std::string_view output);

/// How long sbatch and squeue may take before they are killed.
inline constexpr std::chrono::seconds kSlurmCommandTimeout{60};

/// Submits `script` with `sbatch --parsable` (no shell, kSlurmCommandTimeout) and returns the job
/// id; std::runtime_error with sbatch's own words when it fails.
std::string submitBatch(const std::filesystem::path& script);

/// Slurm's state of a job ("RUNNING", "PENDING", "CANCELLED", ...; "" when Slurm no longer knows
/// it), nothing when squeue could not answer. `job` is "JOBID" or "ARRAYJOB_TASK".
std::optional<std::string> slurmJobState(const std::string& job);

/// Whether a job in this state may still run or write: pending, running, completing, suspended, ...
bool isLiveJobState(std::string_view state);

/// One submission of a sweep's array.
struct Submission {
  std::string job;               ///< the array job id
  std::vector<ArrayTask> tasks;  ///< task i ran tasks[i].runs
  std::string submitted;         ///< UTC, ISO 8601
};

/// Appends a submission to SWEEPDIR/slurm/submitted.json (rewritten atomically).
void recordSubmission(const std::filesystem::path& sweepDir, const Submission& s);
/// Every submission recorded, oldest first (none when the file is missing).
std::vector<Submission> readSubmissions(const std::filesystem::path& sweepDir);

/// The log of array task `task` ("JOB_TASK") under SWEEPDIR/slurm/logs.
std::filesystem::path taskLog(const std::filesystem::path& sweepDir, const std::string& task);

}  // namespace confpack::study
