// `confpack sweep` with the real binary and real physics: a sweep killed with SIGKILL and resumed
// loses no run and redoes none. The sweep engine's bookkeeping is tested in
// tests/study/test_sweep.cpp.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "study/slurm.hpp"
#include "study/sweep.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::ConfpackSession;
using confpack::testing::slurp;

TEST_CASE("a sweep killed with SIGKILL and restarted finishes with no run lost or redone") {
  const ConfpackSession s("cmd_sweep_kill");
  const fs::path& dir = s.dir;
  // Four small, short runs of real physics (the time limit, not equilibrium, ends them).
  std::ofstream(dir / "s.json") << R"({
    "name": "kill",
    "base": { "box": { "length_x": 3, "height": 3 }, "compaction": { "time_limit": 1.5 } },
    "vary": { "width": [3, 4], "seed": [1], "backend": ["nscd", "bullet"] } })";
  const pid_t pid = testing::startConfpack(dir, {"sweep", "s.json", "--out", "sw", "--jobs", "1"});
  REQUIRE(pid >= 0);
  // Kill as soon as the first run is finished (the second is then in progress or about to be).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(dir / "sw" / "runs" / "r0000" / study::kDoneMarker) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(fs::exists(dir / "sw" / "runs" / "r0000" / study::kDoneMarker));

  std::map<std::string, std::string> markers;  // finished before the kill: content must not change
  for (const auto& e : fs::directory_iterator(dir / "sw" / "runs"))
    if (fs::exists(e.path() / study::kDoneMarker))
      markers[e.path().filename().string()] = slurp(e.path() / study::kDoneMarker);
  INFO("finished before the kill: " << markers.size());
  CHECK(markers.size() < 4);

  const auto resumed = s.run("sweep s.json --out sw");
  REQUIRE(resumed.code == 0);
  CHECK(resumed.out.find(std::to_string(markers.size()) + " earlier") != std::string::npos);
  for (const char* r : {"r0000", "r0001", "r0002", "r0003"}) {
    INFO(r);
    CHECK(study::runStatus(dir / "sw" / "runs" / r) == study::RunStatus::Done);
    CHECK(fs::exists(dir / "sw" / "runs" / r / "result.json"));
  }
  for (const auto& [name, text] : markers) CHECK(slurp(dir / "sw" / "runs" / name / study::kDoneMarker) == text);
  // Both backends of a pile read the same deposit file.
  CHECK(fs::exists(dir / "sw" / "deposits" / "d0000.json"));
  CHECK(fs::exists(dir / "sw" / "deposits" / "d0001.json"));
}

// A run stopped mid-compaction (SIGTERM: a task's time limit) goes on from its checkpoint in
// SWEEPDIR/checkpoints/ when the sweep is started again, instead of from its deposit.
TEST_CASE("a sweep stopped by SIGTERM mid-run resumes that run from its checkpoint") {
  const ConfpackSession s("cmd_sweep_checkpoint");
  const fs::path& dir = s.dir;
  std::ofstream(dir / "s.json") << R"({
    "name": "stop",
    "base": { "box": { "length_x": 6, "height": 8 }, "compaction": { "time_limit": 60, "adaptive_dt": true } },
    "vary": { "width": [6], "seed": [1], "backend": ["nscd"] } })";
  const pid_t pid =
      testing::startConfpack(dir, {"sweep", "s.json", "--out", "sw", "--checkpoint-every", "0.001", "-q"});
  REQUIRE(pid >= 0);
  const fs::path state = dir / "sw" / "checkpoints" / "r0000.json";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(state) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(fs::exists(state));
  REQUIRE(study::runStatus(dir / "sw" / "runs" / "r0000") != study::RunStatus::Done);
  // --status says where the run will go on from.
  const auto listed = s.run("sweep sw --status");
  INFO(listed.out << listed.err);
  CHECK_THAT(listed.out, Catch::Contains("r0000   missing"));
  CHECK_THAT(listed.out, Catch::Contains("interrupted; checkpoint: fall at t = "));

  const auto resumed = s.run("sweep s.json --out sw -q");
  INFO(resumed.err);
  REQUIRE(resumed.code == 0);
  REQUIRE(study::runStatus(dir / "sw" / "runs" / "r0000") == study::RunStatus::Done);
  const nlohmann::json result = nlohmann::json::parse(slurp(dir / "sw" / "runs" / "r0000" / "result.json"));
  CHECK(result["timing"]["checkpoint"]["resumes"] == 1);
  CHECK(result["equilibrium"]["reached"] == true);
  CHECK(!fs::exists(state));
  // The marker gives the run's whole wall time, both invocations, and this one's share of it.
  const nlohmann::json done = nlohmann::json::parse(slurp(dir / "sw" / "runs" / "r0000" / "done.json"));
  const double earlier = result["timing"]["checkpoint"]["earlier_s"].get<double>();
  CHECK(earlier > 0.0);
  CHECK(done["wall_s"].get<double>() == Approx(done["wall_s_since_resume"].get<double>() + earlier));
  // What the run measured of itself, compaction and deposit, is part of that.
  CHECK(result["timing"]["wall_s"].get<double>() <= done["wall_s"].get<double>());
}

TEST_CASE("confpack sweep refuses a sweep file listing more runs than --max-runs: one line, exit 2") {
  const ConfpackSession s("cmd_sweep_max_runs");
  std::ofstream(s.dir / "huge.json") << R"({"vary": {"width": [4], "replicas": 100000000}})";
  std::ofstream(s.dir / "two.json") << R"({"vary": {"width": [4, 5]}})";
  const auto huge = s.run("sweep huge.json --list");
  CHECK(huge.code == 2);
  CHECK(huge.err ==
        "confpack sweep: error: huge.json: vary: lists 1e+08 runs, more than the limit of 100000 (check "
        "the lists and replicas, or raise the limit with --max-runs)\n");
  const auto two = s.run("sweep two.json --list --max-runs 1");
  CHECK(two.code == 2);
  CHECK_THAT(two.err, Catch::Contains("lists 2 runs, more than the limit of 1"));
  CHECK(s.run("sweep two.json --list --max-runs 2").code == 0);
  std::vector<std::string> entries = s.entries();
  std::sort(entries.begin(), entries.end());
  CHECK(entries == std::vector<std::string>{"huge.json", "two.json"});  // nothing written
}

TEST_CASE("confpack sweep refuses a run whose analysis would exceed max_cells before any run: one line, exit 2") {
  const ConfpackSession s("cmd_sweep_max_cells");
  std::ofstream(s.dir / "wide.json") << R"({"base": {"box": {"length_x": 2, "height": 1.5}},
                                            "vary": {"width": [4, 20000]}})";
  const auto wide = s.run("sweep wide.json --out sw");
  CHECK(wide.code == 2);
  CHECK_THAT(wide.err, Catch::Contains("wide.json: run r0001 (MSP xS=0 W=20000 mu=0 s1 nscd): analysis: about"));
  CHECK_THAT(wide.err, Catch::Contains("more than max_cells (2e+08)"));
  CHECK(testing::lineCount(wide.err) == 1);
  CHECK(!fs::exists(s.dir / "sw"));
}

TEST_CASE("a sweep over a configuration path: two real runs, listed, run and reported by the setting") {
  const ConfpackSession s("cmd_sweep_setting_axis");
  // Two small piles of pinacoids in the biperiodic box, alpha = 60 and 75 degrees; 1 t0 of compaction.
  std::ofstream(s.dir / "shape.json") << R"({
    "name": "shape",
    "base": { "box": { "length_x": 4, "height": 4 }, "population": { "shape": "pinacoid" },
              "compaction": { "time_limit": 1 } },
    "biperiodic_width": 4,
    "vary": { "width": ["biperiodic"], "population.pinacoid.alpha_deg": [60, 75], "backend": "nscd" } })";
  const auto list = s.run("sweep shape.json --list");
  REQUIRE(list.code == 0);
  CHECK(list.out ==
        "run     deposit family   x_S        W  mu_w   seed backend alpha_deg\n"
        "r0000   d0000   MPP        0      bi4     0      1 nscd    60       \n"
        "r0001   d0001   MPP        0      bi4     0      1 nscd    75       \n");
  REQUIRE(s.run("sweep shape.json --out sw -q").code == 0);
  for (const char* r : {"r0000", "r0001"}) {
    INFO(r);
    REQUIRE(study::runStatus(s.dir / "sw" / "runs" / r) == study::RunStatus::Done);
    const nlohmann::json cfg = nlohmann::json::parse(slurp(s.dir / "sw" / "runs" / r / "config.json"));
    CHECK(cfg["population"]["pinacoid"]["alpha_deg"] == (std::string(r) == "r0000" ? 60.0 : 75.0));
  }
  CHECK_THAT(slurp(s.dir / "sw" / "runs" / "r0001" / study::kDoneMarker),
             Catch::Contains("\"label\": \"MPP xS=0 W=bi4 mu=0 s1 nscd alpha_deg=75\""));
  REQUIRE(s.run("report sw --no-figures").code == 0);
  const std::string md = slurp(s.dir / "sw" / "report" / "report.md");
  CHECK(md.find("| MPP: pinacoids x_S = 0, mu_w = 0, alpha_deg = 60 | nscd |") != std::string::npos);
  CHECK(md.find("| MPP: pinacoids x_S = 0, mu_w = 0, alpha_deg = 75 | nscd |") != std::string::npos);
  CHECK(md.find("## Solid fraction and coordination against alpha_deg") != std::string::npos);
  CHECK(slurp(s.dir / "sw" / "report" / "tables" / "solid_fraction.csv").find(",population.pinacoid.alpha_deg,") !=
        std::string::npos);

  // A path the configuration does not have is bad input: one line naming it, exit 2, nothing written.
  std::ofstream(s.dir / "typo.json") << R"({"vary": {"population.pinacoid.alpha": [60]}})";
  const auto typo = s.run("sweep typo.json --out typo");
  CHECK(typo.code == 2);
  CHECK(typo.err ==
        "confpack sweep: error: typo.json: vary.population.pinacoid.alpha: unknown configuration path: "
        "population.pinacoid has no key alpha (its keys: E, G, alpha_deg)\n");
  CHECK_FALSE(fs::exists(s.dir / "typo"));
}

TEST_CASE("the pinacoid shape study of docs/examples expands to its 15 runs") {
  const ConfpackSession s("cmd_sweep_shape_example");
  const std::string file = std::string(CONFPACK_SOURCE_DIR) + "/docs/examples/pinacoid-shape.json";
  const auto list = s.run("sweep '" + file + "' --list");
  REQUIRE(list.code == 0);
  CHECK(testing::lineCount(list.out) == 1 + 15);  // alpha 45, 60, 75 at E = 0.5; 60, 75 at E = 1; 3 seeds
  CHECK_THAT(list.out, Catch::StartsWith("run     deposit family   x_S        W  mu_w   seed backend E   alpha_deg\n"));
  CHECK(list.out.find("nscd    1   45") == std::string::npos);  // no ridge: not a pinacoid
  CHECK(s.empty());
}

TEST_CASE("confpack sweep --slurm writes the job array over the unfinished runs, bad values write nothing") {
  const ConfpackSession s("cmd_sweep_slurm");
  std::ofstream(s.dir / "s.json") << R"({"name": "sl", "base": {"box": {"length_x": 3, "height": 3},
    "compaction": {"time_limit": 0.2}}, "vary": {"width": [3, 4, 5], "backend": ["nscd", "bullet"]}})";

  // Refused before any work, one line each, nothing written.
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"--slurm --time 2h",
       "confpack sweep: error: --time: expected MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS "
       "(got '2h')\n"},
      {"--slurm --mem 4GB",
       "confpack sweep: error: --mem: expected a positive integer with an optional unit K, M, G "
       "or T (got '4GB')\n"},
      {"--slurm --sbatch-line=--array=1-3",
       "confpack sweep: error: --sbatch-line: --array: not here (the array is the unfinished runs')\n"},
      {"--submit", "confpack sweep: error: --submit requires --slurm (see --help)\n"},
      {"--partition short", "confpack sweep: error: --partition requires --slurm (see --help)\n"},
      {"--slurm --cpus-per-task 0", ""},
      {"--slurm --status", ""},
      {"--slurm --jobs 2", ""}};
  for (const auto& [flags, message] : refused) {
    INFO(flags);
    const auto r = s.run("sweep s.json --out sw " + flags);
    CHECK(r.code == 2);
    CHECK(testing::lineCount(r.err) == 1);
    if (!message.empty()) CHECK(r.err == message);
    CHECK(s.entries() == std::vector<std::string>{"s.json"});
  }

  // Two runs done by hand first: the array takes the other four, one run a task.
  REQUIRE(s.run("sweep s.json --out sw --runs r0000,r0001 -q").code == 0);
  const auto r = s.run(
      "sweep s.json --out sw --slurm --partition short --time 0:30:00 --mem 1G --account lab "
      "--cpus-per-task 2 --array-limit 4 --sbatch-line=--qos=low");
  REQUIRE(r.code == 0);
  const fs::path script = fs::canonical(s.dir / "sw") / "slurm" / "study.sbatch";
  CHECK(r.out == "wrote " + script.string() +
                     ": 4 array tasks over 4 unfinished runs (2 done, 0 running or queued); "
                     "submit with: sbatch " +
                     script.string() + "\n");
  const std::string text = testing::slurp(script);
  CHECK_THAT(text, Catch::Contains("#SBATCH --array=0-3%4\n"));
  CHECK_THAT(text,
             Catch::Contains("#SBATCH --output=" + fs::canonical(s.dir / "sw").string() + "/slurm/logs/%A_%a.out\n"));
  for (const char* line :
       {"#SBATCH --partition=short\n", "#SBATCH --time=0:30:00\n", "#SBATCH --mem=1G\n", "#SBATCH --account=lab\n",
        "#SBATCH --cpus-per-task=2\n", "#SBATCH --qos=low\n", "runs=(\n  r0002\n  r0003\n  r0004\n  r0005\n)\n"})
    CHECK_THAT(text, Catch::Contains(line));
  CHECK_THAT(text, Catch::Contains("exec '" + fs::canonical(CONFPACK_BINARY).string() + "' sweep '" +
                                   fs::canonical(s.dir / "sw").string() +
                                   "' --runs \"${runs[$SLURM_ARRAY_TASK_ID]}\" "
                                   "--jobs 2\n"));
  CHECK(fs::is_directory(s.dir / "sw" / "slurm" / "logs"));

  // A task's own command line: the folder and its runs; a name not in the table is bad input.
  const auto task = s.run("sweep sw --runs r0004 -q");
  CHECK(task.code == 0);
  CHECK(study::runStatus(s.dir / "sw" / "runs" / "r0004") == study::RunStatus::Done);
  CHECK(study::runStatus(s.dir / "sw" / "runs" / "r0005") == study::RunStatus::Pending);
  const auto unknown = s.run("sweep sw --runs r0004,r0099");
  CHECK(unknown.code == 2);
  CHECK(unknown.err == "confpack sweep: error: --runs: no run 'r0099' in the table (r0000 to r0005)\n");

  // The status, and an array over what is left: r0002, r0003, r0005 (never submitted: missing).
  const auto status = s.run("sweep sw --status");
  REQUIRE(status.code == 0);
  CHECK_THAT(status.out, Catch::Contains("r0004   done     -   MSP xS=0 W=5 mu=0 s1 nscd\n"));
  CHECK_THAT(status.out, Catch::Contains("r0005   missing  -   MSP xS=0 W=5 mu=0 s1 bullet\n"));
  CHECK_THAT(status.out, Catch::EndsWith("6 runs: 3 done, 0 running, 0 queued, 0 failed, 3 missing\n"));
  REQUIRE(s.run("sweep sw --slurm -q").code == 0);
  CHECK_THAT(testing::slurp(script), Catch::Contains("runs=(\n  r0002\n  r0003\n  r0005\n)\n"));
}

TEST_CASE("confpack sweep: the runs of one deposit in separate tasks make the same deposit") {
  // One array task a run (study/slurm.hpp): a deposit is made by whichever of its runs comes
  // first, in any task, and must not depend on which. Two tasks at once, each running one backend
  // of the same pile, then the deposit made again by one alone: the same file but for the time it
  // took to make.
  const ConfpackSession s("cmd_sweep_task_deposit");
  std::ofstream(s.dir / "s.json") << R"({"name": "td", "base": {"box": {"length_x": 3, "width": 3, "height": 3},
    "compaction": {"time_limit": 0.2}}, "vary": {"backend": ["nscd", "bullet"]}})";
  // The two processes in one shell line, `first & second; wait` (the second outside the session's
  // `cd`: absolute paths).
  const std::string sweep = "sweep '" + (s.dir / "s.json").string() + "' --out '" + (s.dir / "sw").string() + "'";
  const auto both = s.run(sweep + " --runs r0000 -q & '" + s.program + "' " + sweep + " --runs r0001 -q; wait");
  INFO(both.err);
  REQUIRE(study::runStatus(s.dir / "sw" / "runs" / "r0000") == study::RunStatus::Done);
  REQUIRE(study::runStatus(s.dir / "sw" / "runs" / "r0001") == study::RunStatus::Done);
  const fs::path deposit = s.dir / "sw" / "deposits" / "d0000.json";
  REQUIRE(fs::exists(deposit));
  const auto withoutTime = [&] {
    nlohmann::json j = nlohmann::json::parse(testing::slurp(deposit));
    j.erase("seconds");
    return j.dump();
  };
  const std::string together = withoutTime();
  fs::remove(deposit);
  fs::remove_all(s.dir / "sw" / "runs" / "r0001");
  REQUIRE(s.run("sweep s.json --out sw --runs r0001 -q").code == 0);
  CHECK(withoutTime() == together);
  CHECK(study::runStatus(s.dir / "sw" / "runs" / "r0001") == study::RunStatus::Done);
}

TEST_CASE("confpack sweep --slurm --submit hands the script to sbatch and records the job, its failure exits 1") {
  const ConfpackSession s("cmd_sweep_submit");
  std::ofstream(s.dir / "s.json") << R"({"vary": {"width": [3, 4], "backend": "nscd"}})";
  // A stand-in sbatch first in PATH: it checks its arguments and answers as sbatch --parsable does.
  const fs::path bin = s.dir.string() + ".bin";
  fs::create_directories(bin);
  std::ofstream(bin / "sbatch") << "#!/bin/sh\n"
                                   "grep -q -- '--partition=nowhere' \"$2\" && "
                                   "{ echo 'sbatch: error: invalid partition specified' >&2; exit 1; }\n"
                                   "[ \"$1\" = --parsable ] && grep -q '^#SBATCH --array=0-1$' \"$2\" && echo 4242\n";
  fs::permissions(bin / "sbatch", fs::perms::owner_all);
  const std::string path = std::getenv("PATH");
  ::setenv("PATH", (bin.string() + ":" + path).c_str(), 1);
  const auto ok = s.run("sweep s.json --out sw --slurm --submit");
  const auto again = s.run("sweep sw --slurm --submit --partition nowhere");
  // Both runs queued in job 4242 (squeue is not there: the status says it could not ask).
  const auto status = s.run("sweep sw --status");
  ::setenv("PATH", path.c_str(), 1);
  fs::remove_all(bin);
  REQUIRE(ok.code == 0);
  CHECK_THAT(ok.out, Catch::StartsWith("submitted job 4242: 2 array tasks over 2 unfinished runs (0 done, 0 running "
                                       "or queued); logs in "));
  const auto subs = study::readSubmissions(s.dir / "sw");
  REQUIRE(subs.size() == 1);
  CHECK(subs[0].job == "4242");
  CHECK(subs[0].tasks.size() == 2);
  // Submitted again (squeue is absent: the runs' state is unknown, so they are taken again) to a
  // partition this sbatch refuses: its words, exit 1, no submission recorded.
  CHECK(again.code == 1);
  CHECK(again.err ==
        "confpack sweep: error: sbatch exited with status 1: sbatch: error: invalid partition specified\n");
  CHECK(study::readSubmissions(s.dir / "sw").size() == 1);
  REQUIRE(status.code == 0);
  CHECK_THAT(status.out, Catch::Contains("r0000   missing  4242_0 MSP xS=0 W=3 mu=0 s1 nscd: submitted, but squeue did "
                                         "not answer\n"));
}

TEST_CASE("confpack sweep --reanalyse measures finished runs again and keeps what the compaction wrote") {
  const ConfpackSession s("cmd_sweep_reanalyse");
  std::ofstream(s.dir / "one.json") << R"({
    "name": "one",
    "base": { "box": { "length_x": 4, "height": 7 }, "compaction": { "time_limit": 1 } },
    "biperiodic_width": 4,
    "vary": { "width": ["biperiodic"], "backend": "nscd" } })";
  REQUIRE(s.run("sweep one.json --out sw -q").code == 0);
  const fs::path run = s.dir / "sw" / "runs" / "r0000";
  const nlohmann::json original = nlohmann::json::parse(slurp(run / "result.json"));
  const std::string profile = slurp(run / "phi_y.csv");
  REQUIRE(original.at("solid_fraction").get<double>() > 0.3);

  // The analysis is deterministic and packing.json gives back the final poses' bits: measured
  // again, an untouched run's result.json is the one its compaction wrote.
  const auto again = s.run("sweep sw --reanalyse -q");
  REQUIRE(again.code == 0);
  CHECK(again.out ==
        "sweep one: 1 finished runs analysed again, 0 not finished left to the sweep; report with: "
        "confpack report sw\n");
  CHECK(nlohmann::json::parse(slurp(run / "result.json")) == original);

  // A result.json from an older analysis: a measurement missing (null, as where a box has no bulk
  // region), a block missing, one no longer made; progress lines on.
  nlohmann::json stale = original;
  stale["solid_fraction"] = nullptr;
  stale.erase("coordination");
  stale["retired_block"] = {{"value", 1}};
  std::ofstream(run / "result.json") << stale.dump(2);
  fs::remove(run / "phi_y.csv");
  const auto mend = s.run("sweep sw --reanalyse");
  REQUIRE(mend.code == 0);
  CHECK_THAT(mend.err, Catch::Contains("[1/1] r0000 phi - -> 0."));
  const nlohmann::json mended = nlohmann::json::parse(slurp(run / "result.json"));
  CHECK(mended == original);
  CHECK(slurp(run / "phi_y.csv") == profile);

  // A finished run without its packing: one line naming the file, exit 1, result.json untouched.
  fs::remove(run / "packing.json");
  const auto missing = s.run("sweep sw --reanalyse -q");
  CHECK(missing.code == 1);
  CHECK_THAT(missing.err, Catch::Contains("packing.json"));
  CHECK(std::count(missing.err.begin(), missing.err.end(), '\n') == 1);
  CHECK(nlohmann::json::parse(slurp(run / "result.json")) == original);

  // Not a sweep folder: bad input, exit 2.
  fs::create_directory(s.dir / "empty");
  CHECK(s.run("sweep empty --reanalyse").code == 2);
}
