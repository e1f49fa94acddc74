// A sweep as a Slurm job array (study/slurm.hpp): the batch script for given options, refused
// values, the runs dealt into tasks, sbatch's job id, what squeue's answers mean, the record of
// submissions. The whole chain against a live slurmctld and slurmd: tests/slurm/.
#include <stdlib.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "study/slurm.hpp"
#include "study/sweep.hpp"
#include "tests/support/scratch.hpp"

namespace fs = std::filesystem;
using namespace confpack;

namespace {

// 2 widths x 2 seeds x 2 backends: 8 runs, 4 deposits (both backends of a pile share one).
std::vector<study::SweepRun> eightRuns() {
  return study::expandRuns(study::parseSweepSpec(nlohmann::json::parse(R"({
    "name": "s", "base": { "box": { "length_x": 3, "height": 3 } },
    "vary": { "width": [3, 4], "replicas": 2, "backend": ["nscd", "bullet"] } })")));
}

std::vector<std::vector<std::string>> names(const std::vector<study::ArrayTask>& tasks) {
  std::vector<std::vector<std::string>> out;
  for (const auto& t : tasks) out.push_back(t.runs);
  return out;
}

// PATH for the rest of a test: a folder holding a fake program; the old PATH comes back after.
struct FakePath {
  std::string old = std::getenv("PATH") ? std::getenv("PATH") : "";
  fs::path dir = confpack::testing::freshDir("slurm_fake_path");
  void program(const std::string& name, const std::string& script) {
    std::ofstream(dir / name) << "#!/bin/sh\n" << script << "\n";
    fs::permissions(dir / name, fs::perms::owner_all);
    ::setenv("PATH", (dir.string() + ":/usr/bin:/bin").c_str(), 1);
  }
  void only() { ::setenv("PATH", dir.string().c_str(), 1); }
  ~FakePath() {
    ::setenv("PATH", old.c_str(), 1);
    fs::remove_all(dir);
  }
};

}  // namespace

TEST_CASE("slurm: the batch script carries every option, the logs' folder and each task's runs") {
  study::SlurmOptions o;
  o.partition = "short";
  o.time = "0:10:00";
  o.mem = "2G";
  o.account = "granular-lab";
  o.cpusPerTask = 2;
  o.arrayLimit = 3;
  o.extraLines = {"--qos=low", "--mail-type=END"};
  const std::vector<study::ArrayTask> tasks = {{{"r0000", "r0001"}}, {{"r0003"}}};
  const std::string s =
      study::sbatchScript(o, tasks, "/opt/confpack/bin/../bin/confpack", "/scratch/u/study", "paper scale");
  CHECK(s ==
        "#!/bin/bash\n"
        "# The unfinished runs of sweep paper scale as a Slurm job array, written by `confpack sweep --slurm`: 3 "
        "runs in 2 tasks.\n"
        "# Each task runs `confpack sweep SWEEPDIR --runs LIST`, which skips a run that is finished or held by a "
        "live task, so no run is done twice. docs/cluster.md.\n"
        "#SBATCH --job-name=confpack-paper_scale\n"
        "#SBATCH --array=0-1%3\n"
        "#SBATCH --output=/scratch/u/study/slurm/logs/%A_%a.out\n"
        "#SBATCH --cpus-per-task=2\n"
        "#SBATCH --time=0:10:00\n"
        "#SBATCH --mem=2G\n"
        "#SBATCH --partition=short\n"
        "#SBATCH --account=granular-lab\n"
        "#SBATCH --qos=low\n"
        "#SBATCH --mail-type=END\n"
        "set -euo pipefail\n"
        "runs=(\n"
        "  r0000,r0001\n"
        "  r0003\n"
        ")\n"
        "exec '/opt/confpack/bin/confpack' sweep '/scratch/u/study' --runs \"${runs[$SLURM_ARRAY_TASK_ID]}\" "
        "--jobs 2\n");
  // Without options: the cluster's defaults, one CPU, no limit on the array.
  const std::string plain = study::sbatchScript({}, {{{"r0007"}}}, "/bin/confpack", "/d", "x");
  CHECK(plain.find("#SBATCH --array=0-0\n") != std::string::npos);
  CHECK(plain.find("--time") == std::string::npos);
  CHECK(plain.find("--partition") == std::string::npos);
  CHECK(plain.find("--jobs 1\n") != std::string::npos);
  // A quote in the binary's path stays one word for bash.
  CHECK(study::sbatchScript({}, {{{"r0"}}}, "/o'k/confpack", "/d", "x").find("exec '/o'\\''k/confpack' sweep") !=
        std::string::npos);
  CHECK_THROWS_AS(study::sbatchScript({}, {}, "/bin/confpack", "/d", "x"), std::invalid_argument);
}

TEST_CASE("slurm: a bad option value is refused by its option") {
  const auto refused = [](auto change) {
    study::SlurmOptions o;
    change(o);
    try {
      study::checkSlurmOptions(o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(refused([](auto&) {}).empty());
  CHECK(refused([](auto& o) { o.time = "1-12:30:00"; }).empty());
  CHECK(refused([](auto& o) { o.time = "90"; }).empty());
  CHECK(refused([](auto& o) { o.mem = "512"; }).empty());
  CHECK(refused([](auto& o) { o.time = "2h"; }) ==
        "--time: expected MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS (got '2h')");
  CHECK(refused([](auto& o) { o.mem = "4GB"; }) ==
        "--mem: expected a positive integer with an optional unit K, M, G or T (got '4GB')");
  CHECK(refused([](auto& o) { o.mem = "0"; }).starts_with("--mem:"));
  CHECK(refused([](auto& o) { o.partition = "a b"; }) == "--partition: expected a partition name (got 'a b')");
  CHECK(refused([](auto& o) { o.account = "x;rm"; }).starts_with("--account:"));
  CHECK(refused([](auto& o) { o.cpusPerTask = 0; }) == "--cpus-per-task: must be >= 1 (got 0)");
  CHECK(refused([](auto& o) { o.extraLines = {"--array=0-9"}; }) ==
        "--sbatch-line: --array: not here (the array is the unfinished runs')");
  CHECK(refused([](auto& o) { o.extraLines = {"-o x.log"}; }).starts_with("--sbatch-line: -o: not here (logs go"));
  CHECK(refused([](auto& o) { o.extraLines = {"--time=5"}; }) == "--sbatch-line: --time: not here (use --time)");
  CHECK(refused([](auto& o) { o.extraLines = {"--qos=a\n#SBATCH --array=1"}; }) == "--sbatch-line: must be one line");
  CHECK(refused([](auto& o) { o.extraLines = {"qos=low"}; }).starts_with("--sbatch-line: expected an sbatch option"));
  CHECK_NOTHROW(study::checkSlurmPath("/scratch/u/study-1"));
  CHECK_THROWS_WITH(study::checkSlurmPath("/scratch/my study"), Catch::Contains("cannot go into an #SBATCH line"));
  CHECK_THROWS_AS(study::checkSlurmPath("/scratch/100%"), std::invalid_argument);
}

TEST_CASE("slurm: the runs given are dealt one per task, or over at most K tasks") {
  // One run a task, so that the study's wall time is its slowest run's; runs of one deposit go to
  // different tasks, each reading or making the deposit.
  const auto runs = eightRuns();
  REQUIRE(runs.size() == 8);
  REQUIRE(runs[0].depositIndex == runs[1].depositIndex);
  // r0002 is done.
  const std::vector<std::size_t> todo = {0, 1, 3, 4, 5, 6, 7};
  CHECK(names(study::planArrayTasks(runs, todo)) ==
        std::vector<std::vector<std::string>>{
            {"r0000"}, {"r0001"}, {"r0003"}, {"r0004"}, {"r0005"}, {"r0006"}, {"r0007"}});
  CHECK(names(study::planArrayTasks(runs, todo, 3)) ==
        std::vector<std::vector<std::string>>{{"r0000", "r0004", "r0007"}, {"r0001", "r0005"}, {"r0003", "r0006"}});
  CHECK(names(study::planArrayTasks(runs, {5}, 3)) == std::vector<std::vector<std::string>>{{"r0005"}});
  CHECK(study::planArrayTasks(runs, {}).empty());
}

TEST_CASE("slurm: with equal_time a Bullet run shares its nscd partner's task") {
  // Its run needs the partner's fall time: apart, a task could start before the partner ended.
  const auto runs = eightRuns();
  const auto partners = study::equalTimePartners(runs, "nscd");
  const std::vector<std::size_t> todo = {0, 1, 3, 4, 5, 6, 7};  // r0002 (nscd, seed 2) is done
  CHECK(names(study::planArrayTasks(runs, todo, 0, partners)) ==
        std::vector<std::vector<std::string>>{{"r0000", "r0001"}, {"r0003"}, {"r0004", "r0005"}, {"r0006", "r0007"}});
  CHECK(names(study::planArrayTasks(runs, todo, 2, partners)) ==
        std::vector<std::vector<std::string>>{{"r0000", "r0001", "r0004", "r0005"}, {"r0003", "r0006", "r0007"}});
}

TEST_CASE("slurm: sbatch's job id, and what squeue's answers mean") {
  CHECK(study::jobIdFromSbatch("1234\n") == "1234");
  CHECK(study::jobIdFromSbatch("sbatch: warning: can't honor --mem\n77;cluster2\n") == "77");
  CHECK_THROWS_WITH(study::jobIdFromSbatch("sbatch: error: invalid partition\n"),
                    "sbatch printed no job id (its output: 'sbatch: error: invalid partition')");
  CHECK(study::isLiveJobState("RUNNING"));
  CHECK(study::isLiveJobState("PENDING"));
  CHECK(study::isLiveJobState("COMPLETING"));
  CHECK_FALSE(study::isLiveJobState("CANCELLED"));
  CHECK_FALSE(study::isLiveJobState("TIMEOUT"));
  CHECK_FALSE(study::isLiveJobState(""));

  FakePath path;
  path.program("squeue", R"(case "$*" in *"--jobs 12_3"*) echo RUNNING ;; *"--jobs 12_4"*) echo "TIMEOUT" ;;
  *) echo "slurm_load_jobs error: Invalid job id specified" >&2; exit 1 ;; esac)");
  CHECK(study::slurmJobState("12_3") == std::optional<std::string>("RUNNING"));
  CHECK(study::slurmJobState("12_4") == std::optional<std::string>("TIMEOUT"));
  CHECK(study::slurmJobState("99") == std::optional<std::string>(""));  // forgotten: ended
  path.program("squeue", R"(echo "slurm_load_jobs error: Unable to contact slurm controller" >&2; exit 1)");
  CHECK_FALSE(study::slurmJobState("12_3"));
  path.only();  // no squeue at all
  CHECK_FALSE(study::slurmJobState("12_3"));
}

TEST_CASE("slurm: submitting runs sbatch without a shell and records the job, a refusal says sbatch's words") {
  const fs::path dir = confpack::testing::freshDir("slurm_submit");
  fs::create_directories(dir / "slurm");
  std::ofstream(dir / "slurm" / "study.sbatch") << "#!/bin/bash\n";
  FakePath path;
  path.program("sbatch", R"([ "$1" = --parsable ] && [ -f "$2" ] && echo "4711;main")");
  CHECK(study::submitBatch(dir / "slurm" / "study.sbatch") == "4711");
  path.program("sbatch", R"(echo "sbatch: error: Batch job submission failed: Invalid account" >&2; exit 1)");
  CHECK_THROWS_WITH(study::submitBatch(dir / "slurm" / "study.sbatch"),
                    "sbatch exited with status 1: sbatch: error: Batch job submission failed: Invalid account");
  // Nothing of sbatch's output is left beside the script.
  CHECK(std::distance(fs::directory_iterator(dir / "slurm"), fs::directory_iterator()) == 1);

  CHECK(study::readSubmissions(dir).empty());
  study::recordSubmission(dir, {"40", {{{"r0000", "r0001"}}, {{"r0002"}}}, "2024-01-01T00:00:00Z"});
  study::recordSubmission(dir, {"41", {{{"r0002"}}}, ""});
  const auto subs = study::readSubmissions(dir);
  REQUIRE(subs.size() == 2);
  CHECK(subs[0].job == "40");
  CHECK(subs[0].submitted == "2024-01-01T00:00:00Z");
  CHECK(subs[0].tasks.size() == 2);
  CHECK(subs[0].tasks[0].runs == std::vector<std::string>{"r0000", "r0001"});
  CHECK(subs[1].job == "41");
  CHECK(subs[1].submitted.size() == 20);  // stamped now: 2024-05-01T12:00:00Z
  CHECK(study::taskLog(dir, "41_0") == dir / "slurm" / "logs" / "41_0.out");
  std::ofstream(dir / "slurm" / "submitted.json") << R"({"format": "other"})";
  CHECK_THROWS_WITH(study::readSubmissions(dir),
                    Catch::EndsWith("submitted.json: format: must be \"confpack-slurm-submissions\" (got \"other\")"));
  std::ofstream(dir / "slurm" / "submitted.json")
      << R"({"format": "confpack-slurm-submissions", "version": 1, "submissions": [{"job": "40", "tasks": [["r0000", 3]]}]})";
  CHECK_THROWS_WITH(study::readSubmissions(dir),
                    Catch::EndsWith("submitted.json: submissions[0].tasks: must be an array of arrays of run names"));
  fs::remove_all(dir);
}
