// Where each run stands (study/sweep_status.hpp): the classification from a run's facts, and the
// status of a sweep folder with markers, claims, submissions and logs in place.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "study/slurm.hpp"
#include "study/sweep_status.hpp"
#include "tests/support/scratch.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using study::Liveness;
using study::RunState;
using study::RunStatus;

namespace {

study::ClaimHolder holder(std::string job) {
  return {"node3", 4711, 0, std::move(job), "t", "2024-01-01T10:00:00Z"};
}

}  // namespace

TEST_CASE("status: a run's state from its markers, claim and Slurm task, in order") {
  study::RunFacts f;
  CHECK(study::classifyRun(f).state == RunState::Missing);
  CHECK(study::classifyRun(f).detail.empty());
  f.markers = RunStatus::Incomplete;
  CHECK(study::classifyRun(f).detail == "interrupted");
  // With a checkpoint, where the next attempt goes on from (not for a run that is done).
  f.checkpoint = "checkpoint: fall at t = 83.5, 12 min";
  CHECK(study::classifyRun(f).detail == "interrupted; checkpoint: fall at t = 83.5, 12 min");
  f.markers = RunStatus::Done;
  CHECK(study::classifyRun(f).detail.empty());
  f.markers = RunStatus::Incomplete;
  f.checkpoint.clear();

  // Handed to a task Slurm still lists: queued.
  f.task = "12_3";
  f.taskState = "PENDING";
  CHECK(study::classifyRun(f).state == RunState::Queued);
  CHECK(study::classifyRun(f).job == "12_3");
  // The task ended without finishing it: failed, with the log's last line.
  f.taskState = "";
  f.taskLogLine = "slurmstepd: error: *** JOB 15 ON vm CANCELLED AT 2024-01-01T10:05:00 DUE TO TIME LIMIT ***";
  study::RunReport r = study::classifyRun(f);
  CHECK(r.state == RunState::Failed);
  CHECK(r.detail == "its task ended without finishing it: " + f.taskLogLine);
  // squeue did not answer: nothing is claimed about the task.
  f.taskState.reset();
  CHECK(study::classifyRun(f).state == RunState::Missing);
  CHECK(study::classifyRun(f).detail == "submitted, but squeue did not answer");

  // A claim whose holder lives: running, with its job.
  f.claim = holder("12_3");
  f.claimHolder = Liveness::Alive;
  r = study::classifyRun(f);
  CHECK(r.state == RunState::Running);
  CHECK(r.job == "12_3");
  CHECK(r.detail == "node3 pid 4711 (job 12_3) since 2024-01-01T10:00:00Z");
  f.claimHolder = Liveness::Unknown;
  CHECK(study::classifyRun(f).state == RunState::Running);
  // Its holder died: failed, with the log's last line.
  f.claimHolder = Liveness::Dead;
  r = study::classifyRun(f);
  CHECK(r.state == RunState::Failed);
  CHECK(r.detail == "node3 pid 4711 (job 12_3) died without finishing it: " + f.taskLogLine);

  // failed.json: its error, unless a live task was submitted for it after it failed.
  f.claim.reset();
  f.markers = RunStatus::Failed;
  f.failedError = "deposit: 56 grains, more than max_grains = 5";
  f.failedAt = "2024-01-01T10:02:00Z";
  f.taskState = "RUNNING";
  f.taskSubmitted = "2024-01-01T10:00:00Z";  // the task that failed it, still running others
  r = study::classifyRun(f);
  CHECK(r.state == RunState::Failed);
  CHECK(r.detail == f.failedError);
  f.taskSubmitted = "2024-01-01T11:00:00Z";  // a new array, after the failure
  r = study::classifyRun(f);
  CHECK(r.state == RunState::Queued);
  CHECK(r.detail == "RUNNING; it failed before: " + f.failedError);

  // done.json wins over everything.
  f.markers = RunStatus::Done;
  f.claim = holder("12_3");
  f.claimHolder = Liveness::Alive;
  CHECK(study::classifyRun(f).state == RunState::Done);

  std::vector<study::RunReport> reports(5);
  reports[0].state = RunState::Done;
  reports[1].state = RunState::Running;
  reports[2].state = RunState::Queued;
  reports[3].state = RunState::Failed;
  reports[4].state = RunState::Missing;
  CHECK(study::unfinishedRuns(reports) == std::vector<std::size_t>{3, 4});
}

TEST_CASE("status: a sweep folder's runs, from markers, claims, submissions and task logs") {
  const fs::path dir = confpack::testing::freshDir("sweep_status");
  const study::SweepSpec spec = study::parseSweepSpec(nlohmann::json::parse(R"({
    "name": "s", "base": { "box": { "length_x": 3, "height": 3 } },
    "vary": { "width": [3, 4, 5, 6, 7], "backend": ["nscd"] } })"));
  const auto runs = study::expandRuns(spec);
  study::prepareSweepDir(dir, spec, runs);
  // r0000 done; r0001 failed.json; r0002 claimed by a live task; r0003 handed to a task that was
  // cancelled (its log says so); r0004 never run.
  fs::create_directories(dir / "runs" / "r0000");
  std::ofstream(dir / "runs" / "r0000" / study::kDoneMarker) << "{}";
  fs::create_directories(dir / "runs" / "r0001");
  std::ofstream(dir / "runs" / "r0001" / study::kFailedMarker)
      << R"({"error": "bad deposit", "finished": "2024-01-01T10:01:00Z"})";
  fs::create_directories(study::claimsDir(dir));
  std::ofstream(study::claimsDir(dir) / "r0002") << study::toJson(holder("7_2")).dump();
  study::recordSubmission(dir, {"7", {{{"r0000"}}, {{"r0001"}}, {{"r0002"}}, {{"r0003"}}}, "2024-01-01T10:00:00Z"});
  fs::create_directories(dir / "slurm" / "logs");
  std::ofstream(study::taskLog(dir, "7_3")) << "sweep s: 1 runs\nslurmstepd: error: *** JOB 9 CANCELLED ***\n\n";
  // r0004's own run finished and is kept for its settle (settle_with), which has not begun.
  fs::create_directories(study::sweepKeptRunFolder(dir, "r0004"));
  std::ofstream(study::sweepKeptRunFolder(dir, "r0004") / "result.json") << "{}";
  int asked = 0;
  const auto reports = study::sweepStatus(
      dir, runs, [](const study::ClaimHolder&) { return Liveness::Alive; },
      [&](const std::string& job) -> std::optional<std::string> {
        ++asked;
        return job == "7_2" ? "RUNNING" : "";
      });
  REQUIRE(reports.size() == 5);
  CHECK(reports[0].state == RunState::Done);
  CHECK(reports[1].state == RunState::Failed);
  CHECK(reports[1].detail == "bad deposit");
  CHECK(reports[2].state == RunState::Running);
  CHECK(reports[2].job == "7_2");
  CHECK(reports[3].state == RunState::Failed);
  CHECK(reports[3].job == "7_3");
  CHECK(reports[3].detail == "its task ended without finishing it: slurmstepd: error: *** JOB 9 CANCELLED ***");
  CHECK(reports[4].state == RunState::Missing);
  CHECK(reports[4].detail == "its own run done, kept for its settle");
  CHECK(asked == 3);  // the tasks of r0001, r0002 and r0003; none for a run done
  const std::string text = study::formatStatus(runs, reports);
  CHECK(text.find("r0002   running  7_2 MSP xS=0 W=5 mu=0 s1 nscd: node3 pid 4711 (job 7_2) since") !=
        std::string::npos);
  CHECK(text.find("r0004   missing  -   MSP xS=0 W=7 mu=0 s1 nscd: its own run done, kept for its settle\n") !=
        std::string::npos);
  CHECK(text.find("5 runs: 1 done, 1 running, 0 queued, 2 failed, 1 missing\n") != std::string::npos);
  fs::remove_all(dir);
}
