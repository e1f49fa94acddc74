#include "study/sweep_status.hpp"

#include <fmt/format.h>

#include <map>
#include <sstream>

#include "compaction/checkpoint.hpp"
#include "core/json_input.hpp"
#include "study/process.hpp"
#include "study/slurm.hpp"

namespace confpack::study {

namespace fs = std::filesystem;

std::string_view toString(RunState s) {
  switch (s) {
    case RunState::Done:
      return "done";
    case RunState::Running:
      return "running";
    case RunState::Queued:
      return "queued";
    case RunState::Failed:
      return "failed";
    case RunState::Missing:
      return "missing";
  }
  return "?";
}

namespace {

RunReport classifyUnfinished(const RunFacts& f) {
  if (f.claim && f.claimHolder != Liveness::Dead)
    return {RunState::Running, f.claim->job,
            fmt::format("{} since {}{}", describe(*f.claim), f.claim->since,
                        f.claimHolder == Liveness::Unknown ? " (cannot check that it is alive from here)" : "")};
  const bool taskLive = !f.task.empty() && f.taskState && isLiveJobState(*f.taskState);
  if (f.markers == RunStatus::Failed) {
    // Handed to a new array after it failed: waiting for its second chance. ISO 8601 times in UTC
    // compare as text; in the same second the failure is taken as the task's own.
    if (taskLive && f.taskSubmitted > f.failedAt)
      return {RunState::Queued, f.task, fmt::format("{}; it failed before: {}", *f.taskState, f.failedError)};
    return {RunState::Failed, f.task, f.failedError};
  }
  if (taskLive) return {RunState::Queued, f.task, *f.taskState};
  const std::string log = f.taskLogLine.empty() ? std::string() : ": " + f.taskLogLine;
  if (f.claim)
    return {RunState::Failed, f.claim->job, fmt::format("{} died without finishing it{}", describe(*f.claim), log)};
  if (!f.task.empty() && f.taskState)
    return {RunState::Failed, f.task, fmt::format("its task ended without finishing it{}", log)};
  if (!f.task.empty()) return {RunState::Missing, f.task, "submitted, but squeue did not answer"};
  return {RunState::Missing, "", f.markers == RunStatus::Incomplete ? "interrupted" : ""};
}

}  // namespace

RunReport classifyRun(const RunFacts& f) {
  if (f.markers == RunStatus::Done) return {RunState::Done, "", ""};
  RunReport r = classifyUnfinished(f);
  if (!f.checkpoint.empty()) r.detail = r.detail.empty() ? f.checkpoint : r.detail + "; " + f.checkpoint;
  return r;
}

std::vector<RunReport> sweepStatus(const fs::path& dir, const std::vector<SweepRun>& runs, const LivenessFn& alive,
                                   const JobStateFn& jobState) {
  // The task each run was last handed to: later submissions override earlier ones.
  std::map<std::string, std::pair<std::string, std::string>> taskOf;  // run -> (task, submitted)
  for (const Submission& s : readSubmissions(dir))
    for (std::size_t t = 0; t < s.tasks.size(); ++t)
      for (const std::string& r : s.tasks[t].runs) taskOf[r] = {fmt::format("{}_{}", s.job, t), s.submitted};
  std::map<std::string, std::optional<std::string>> states;  // one squeue per task
  std::vector<RunReport> out;
  for (const SweepRun& r : runs) {
    RunFacts f;
    const fs::path runDir = dir / "runs" / r.name;
    f.markers = runStatus(runDir);
    if (f.markers == RunStatus::Done) {
      out.push_back(classifyRun(f));
      continue;
    }
    if (f.markers == RunStatus::Failed) {
      try {
        const nlohmann::json marker = core::readJsonFile(runDir / kFailedMarker, "failed marker");
        f.failedError = marker.value("error", std::string());
        f.failedAt = marker.value("finished", std::string());
      } catch (const std::exception& e) {
        f.failedError = e.what();
      }
    }
    f.claim = readClaim(claimsDir(dir), r.name);
    if (f.claim) f.claimHolder = alive(*f.claim);
    if (const auto it = taskOf.find(r.name); it != taskOf.end()) {
      f.task = it->second.first;
      f.taskSubmitted = it->second.second;
      if (!states.count(f.task)) states[f.task] = jobState(f.task);
      f.taskState = states[f.task];
    }
    const std::string logOf = f.claim && !f.claim->job.empty() ? f.claim->job : f.task;
    if (!logOf.empty()) f.taskLogLine = lastOutputLine(taskLog(dir, logOf));
    f.checkpoint = compaction::describeCheckpoint(sweepCheckpointFile(dir, r.name));
    // With settle_with: the run's own part done and kept, and where its settle stands.
    if (fs::exists(sweepKeptRunFolder(dir, r.name) / "result.json"))
      f.checkpoint = "its own run done, kept for its settle";
    if (const std::string settle = compaction::describeCheckpoint(sweepSettleCheckpointFile(dir, r.name));
        !settle.empty())
      f.checkpoint = (f.checkpoint.empty() ? "" : f.checkpoint + "; ") + "the settle's " + settle;
    out.push_back(classifyRun(f));
  }
  return out;
}

std::vector<std::size_t> unfinishedRuns(const std::vector<RunReport>& reports) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < reports.size(); ++i)
    if (reports[i].state == RunState::Failed || reports[i].state == RunState::Missing) out.push_back(i);
  return out;
}

std::string formatStatus(const std::vector<SweepRun>& runs, const std::vector<RunReport>& reports) {
  const std::vector<std::string> varied = variedSettings(runs);
  std::size_t jobWidth = 3;
  for (const RunReport& r : reports) jobWidth = std::max(jobWidth, r.job.size());
  std::map<RunState, std::size_t> counts;
  std::ostringstream out;
  out << fmt::format("{:<7} {:<8} {:<{}} {}\n", "run", "state", "job", jobWidth, "label");
  for (std::size_t i = 0; i < runs.size() && i < reports.size(); ++i) {
    const RunReport& r = reports[i];
    ++counts[r.state];
    out << fmt::format("{:<7} {:<8} {:<{}} {}{}\n", runs[i].name, toString(r.state), r.job.empty() ? "-" : r.job,
                       jobWidth, runs[i].label(varied), r.detail.empty() ? "" : ": " + r.detail);
  }
  out << fmt::format("{} runs: {} done, {} running, {} queued, {} failed, {} missing\n", runs.size(),
                     counts[RunState::Done], counts[RunState::Running], counts[RunState::Queued],
                     counts[RunState::Failed], counts[RunState::Missing]);
  return out.str();
}

}  // namespace confpack::study
