// `confpack sweep FILE`: runs a study described by a sweep file (docs/sweeps.md), resumably, in
// parallel (--jobs) or as one slice of a cluster job array (--task-index/--task-count, or --runs);
// writes and submits a Slurm job array over its unfinished runs (--slurm, --submit) and shows where
// each run stands (--status; docs/cluster.md).
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <set>

#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "backends/backend_factory.hpp"
#include "core/packing_io.hpp"
#include "study/run_pipeline.hpp"
#include "study/slurm.hpp"
#include "study/sweep.hpp"
#include "study/sweep_runner.hpp"
#include "study/sweep_status.hpp"

namespace confpack::app {

namespace {

struct SweepState {
  std::filesystem::path file;
  std::filesystem::path out;
  int jobs = 1;
  int threads = 0;
  double checkpointEvery = compaction::Checkpointing{}.everySeconds;  ///< --checkpoint-every
  std::size_t taskIndex = 0;
  std::size_t taskCount = 1;
  bool list = false;
  bool quiet = false;
  std::size_t maxRuns = study::kDefaultMaxRuns;
  std::string runList;  ///< --runs: names, comma-separated
  bool status = false;
  bool reanalyse = false;  ///< --reanalyse
  bool slurm = false;
  bool submit = false;
  study::SlurmOptions slurmOptions;
};

namespace fs = std::filesystem;

// --runs "r0001,r0004": the runs' indices in the table, each once.
std::vector<std::size_t> namedRuns(const std::vector<study::SweepRun>& runs, const std::string& list) {
  std::map<std::string, std::size_t> index;
  for (const study::SweepRun& r : runs) index[r.name] = r.index;
  std::set<std::size_t> picked;
  for (std::size_t at = 0; at <= list.size();) {
    const std::size_t end = std::min(list.find(',', at), list.size());
    const std::string name = list.substr(at, end - at);
    at = end + 1;
    if (name.empty()) continue;
    const auto it = index.find(name);
    if (it == index.end())
      throw std::invalid_argument(
          fmt::format("--runs: no run '{}' in the table ({} to {})", name, runs.front().name, runs.back().name));
    picked.insert(it->second);
  }
  if (picked.empty()) throw std::invalid_argument("--runs: no run named");
  return {picked.begin(), picked.end()};
}

// Writes SWEEPDIR/slurm/study.sbatch over the runs that are neither done nor in a live job, and
// with --submit hands it to sbatch.
void writeSlurmArray(const SweepState& st, const study::SweepSpec& spec, const std::vector<study::SweepRun>& runs,
                     const fs::path& out) {
  runWork("sweep", [&] {
    const WorkStep step("writing the Slurm job array");
    markOutputFolder(out);
    study::prepareSweepDir(out, spec, runs);
    const std::vector<study::RunReport> reports = study::sweepStatus(out, runs);
    const std::vector<std::size_t> todo = study::unfinishedRuns(reports);
    std::size_t done = 0;
    for (const study::RunReport& r : reports) done += r.state == study::RunState::Done;
    const std::size_t live = runs.size() - done - todo.size();
    if (todo.empty()) {
      fmt::print("sweep {}: nothing to submit: {} of {} runs done, {} running or queued\n", spec.name, done,
                 runs.size(), live);
      return;
    }
    const std::vector<study::ArrayTask> tasks =
        study::planArrayTasks(runs, todo, st.slurmOptions.maxTasks, study::equalTimePartners(runs, spec.equalTime));
    const fs::path dir = fs::absolute(out).lexically_normal();
    fs::create_directories(dir / "slurm" / "logs");  // sbatch does not create the logs' folder
    const fs::path script = dir / "slurm" / "study.sbatch";
    core::writeFileAtomically(
        script, study::sbatchScript(st.slurmOptions, tasks, fs::read_symlink("/proc/self/exe"), dir, spec.name));
    fs::permissions(script, fs::perms::owner_exec, fs::perm_options::add);
    const std::string others = fmt::format("{} done, {} running or queued", done, live);
    if (!st.submit) {
      fmt::print("wrote {}: {} array tasks over {} unfinished runs ({}); submit with: sbatch {}\n", script.string(),
                 tasks.size(), todo.size(), others, script.string());
      return;
    }
    const std::string job = study::submitBatch(script);
    study::recordSubmission(dir, {job, tasks, ""});
    fmt::print(
        "submitted job {}: {} array tasks over {} unfinished runs ({}); logs in {}; progress: confpack sweep {} "
        "--status\n",
        job, tasks.size(), todo.size(), others, (dir / "slurm" / "logs").string(), dir.string());
  });
}

// --reanalyse: every finished run (or those of --runs), and its settle, measured again from its
// packing.json, one after another (a run's analysis takes seconds against its compaction's minutes
// to hours); runs not finished are left to the sweep.
void reanalyseRuns(const SweepState& st, const study::SweepSpec& spec, const std::vector<study::SweepRun>& runs,
                   const fs::path& out, const std::vector<std::size_t>& only) {
  std::vector<std::size_t> done;
  std::size_t notDone = 0;
  for (const study::SweepRun& r : runs) {
    if (!only.empty() && std::find(only.begin(), only.end(), r.index) == only.end()) continue;
    if (study::runStatus(out / "runs" / r.name) == study::RunStatus::Done)
      done.push_back(r.index);
    else
      ++notDone;
  }
  // A run without a bulk region has no solid fraction (null).
  const auto phi = [](const nlohmann::json& result) {
    const auto it = result.find("solid_fraction");
    return it != result.end() && it->is_number() ? fmt::format("{:.4f}", it->get<double>()) : std::string("-");
  };
  runWork("sweep", [&] {
    const WorkStep step("analysing the finished runs again");
    for (std::size_t k = 0; k < done.size(); ++k) {
      const study::SweepRun& r = runs[done[k]];
      const fs::path dir = out / "runs" / r.name;
      const study::Reanalysed again = study::reanalyseRun(dir);
      if (!st.quiet)
        fmt::print(stderr, "[{}/{}] {} phi {} -> {}\n", k + 1, done.size(), r.name, phi(again.before),
                   phi(again.after));
      // The run's settle (settle_with), so that the report compares piles measured alike.
      if (fs::exists(dir / study::kSettledFolder / "result.json")) {
        const study::Reanalysed settled = study::reanalyseRun(dir / study::kSettledFolder);
        if (!st.quiet)
          fmt::print(stderr, "[{}/{}] {}/{} phi {} -> {}\n", k + 1, done.size(), r.name, study::kSettledFolder,
                     phi(settled.before), phi(settled.after));
      }
    }
  });
  fmt::print(
      "sweep {}: {} finished runs analysed again, {} not finished left to the sweep; report with: confpack "
      "report {}\n",
      spec.name, done.size(), notDone, out.string());
}

void runSweepCommand(const SweepState& st) {
  study::SweepSpec spec;
  std::vector<study::SweepRun> runs;
  // FILE may be a sweep folder: its sweep.json holds the sweep file (the array tasks' form).
  const bool folder = fs::is_directory(st.file);
  const fs::path out = folder ? st.file : st.out.empty() ? fs::path(st.file.stem()) : st.out;
  std::vector<std::size_t> only;
  checkInput("sweep", [&] {
    if (folder && !st.out.empty() && fs::absolute(st.out).lexically_normal() != fs::absolute(out).lexically_normal())
      throw std::invalid_argument(
          fmt::format("--out: {} is a sweep folder already; give no other --out", st.file.string()));
    if (folder)
      study::readRunTable(st.file, &spec);
    else
      spec = study::readSweepSpec(st.file, st.maxRuns);
    runs = study::expandRuns(spec);
    study::sliceRuns(runs, st.taskIndex, st.taskCount);  // validates the slice
    try {
      study::equalTimePartners(runs, spec.equalTime);  // with equal_time, every run has its partner
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("{}: {}", st.file.string(), e.what()));
    }
    // The sweep file leaves backend_options to the backend: checked here, so that a typo is bad
    // input (exit 2) rather than a failure of every run.
    const std::vector<std::string> varied = study::variedSettings(runs);
    for (const study::SweepRun& run : runs) {
      std::string_view what = "backend_options: ";
      try {
        backends::checkBackendOptions(run.config.backend, run.config.backendOptions);
        what = "";
        study::checkRunCells(run.config, run.config.estimatedGrainCount());
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(
            fmt::format("{}: run {} ({}): {}{}", st.file.string(), run.name, run.label(varied), what, e.what()));
      }
    }
    if (st.jobs < 1) throw std::invalid_argument(fmt::format("--jobs must be >= 1 (got {})", st.jobs));
    // A sweep folder (it holds the run table) is confpack's, marked or not: resuming is the point.
    if (!fs::exists(out / study::kSweepTable)) checkOutputTarget(out);
    if (!st.runList.empty()) only = namedRuns(runs, st.runList);
    if (st.slurm) {
      study::checkSlurmOptions(st.slurmOptions);
      study::checkSlurmPath(out);
    }
    if ((st.status || st.reanalyse) && !fs::exists(out / study::kSweepTable))
      throw std::invalid_argument(
          fmt::format("{}: not a sweep folder (no {}): nothing has run", out.string(), study::kSweepTable));
  });
  if (st.status) {
    runWork("sweep", [&] { std::fputs(study::formatStatus(runs, study::sweepStatus(out, runs)).c_str(), stdout); });
    return;
  }
  if (st.reanalyse) {
    reanalyseRuns(st, spec, runs, out, only);
    return;
  }
  if (st.slurm) {
    writeSlurmArray(st, spec, runs, out);
    return;
  }
  if (st.list) {
    const bool sliced = st.taskCount > 1;
    std::fputs(
        study::formatRunTable(runs, std::filesystem::exists(out / study::kSweepTable) ? out : std::filesystem::path{},
                              sliced ? std::optional<std::size_t>(st.taskIndex) : std::nullopt, st.taskCount)
            .c_str(),
        stdout);
    return;
  }
  study::SweepSummary summary;
  runWork("sweep", [&] {
    const WorkStep step("running the sweep");
    study::SweepOptions opt;
    opt.jobs = st.jobs;
    opt.taskIndex = st.taskIndex;
    opt.taskCount = st.taskCount;
    opt.runs = only;
    opt.quiet = st.quiet;
    opt.live = ::isatty(STDERR_FILENO) != 0;
    markOutputFolder(out);
    summary = study::runSweep(spec, out, opt, study::pipelineRunner(st.threads, st.checkpointEvery, spec.settleWith),
                              study::pipelineDepositor());
  });
  if (summary.failed > 0) {
    fmt::print(
        stderr,
        "confpack sweep: error: {} run(s) failed (see runs/*/failed.json); run the same command again to retry them\n",
        summary.failed);
    throw CLI::RuntimeError(kExitRuntimeFailure);
  }
  fmt::print("sweep {}: {} of {} runs in this task finished ({} now, {} earlier{}); report with: confpack report {}\n",
             spec.name, summary.ran + summary.alreadyDone, summary.inSlice, summary.ran, summary.alreadyDone,
             summary.heldElsewhere > 0 ? fmt::format(", {} left to other live tasks", summary.heldElsewhere) : "",
             out.string());
}

}  // namespace

void registerSweep(CLI::App& app) {
  auto st = std::make_shared<SweepState>();
  auto* sub = app.add_subcommand(
      "sweep",
      "Run a study: every combination of widths, shapes, fractions, frictions, seeds, backends and any other "
      "configuration key (by its path, e.g. population.pinacoid.alpha_deg) of a sweep file (docs/sweeps.md). "
      "Resumable: finished runs are never redone.");
  sub->add_option("file", st->file,
                  "Sweep file (JSON, format confpack-sweep), or a sweep folder (its sweep.json holds the file)")
      ->required()
      ->check(CLI::ExistingPath);
  sub->add_option("--out", st->out, "Sweep folder (default: the sweep file's name without extension)");
  auto* jobs = sub->add_option("--jobs,-j", st->jobs, "Runs at the same time")->check(CLI::Range(1, 4096));
  sub->add_option("--threads", st->threads, "Threads per run (0: from the sweep file)")->check(CLI::Range(0, 4096));
  sub->add_option("--checkpoint-every", st->checkpointEvery,
                  "Each run saves its state in SWEEPDIR/checkpoints/ at the first equilibrium check after this many "
                  "seconds of wall time and when SIGINT or SIGTERM stops it; the next invocation resumes it there "
                  "(docs/model.md, \"Checkpoints\")")
      ->check(CLI::PositiveNumber)
      ->capture_default_str()
      ->type_name("SECONDS");
  auto* taskIndex =
      sub->add_option("--task-index", st->taskIndex, "This task's slice, 0-based (e.g. $SLURM_ARRAY_TASK_ID)");
  auto* taskCount =
      sub->add_option("--task-count", st->taskCount, "Number of tasks sharing the sweep (e.g. $SLURM_ARRAY_TASK_COUNT)")
          ->check(CLI::Range(1, 1000000));
  auto* runList = sub->add_option("--runs", st->runList,
                                  "Run only these runs, by name, comma-separated (what a task of --slurm's array runs)")
                      ->type_name("r0000,r0001")
                      ->excludes(taskIndex)
                      ->excludes(taskCount);
  auto* list =
      sub->add_flag("--list", st->list, "Print the run table (with each run's status when the folder exists) and exit");
  auto* status = sub->add_flag("--status", st->status,
                               "Print where each run stands (done, running with its job, queued, failed with the "
                               "reason, missing) and exit")
                     ->excludes(list)
                     ->excludes(runList);
  auto* reanalyse = sub->add_flag("--reanalyse", st->reanalyse,
                                  "Analyse every finished run's packing.json again with this version (its "
                                  "measurements and profiles; the compaction's blocks of result.json are kept), so "
                                  "that a study run over several versions is reported with one analysis, and exit")
                        ->excludes(list)
                        ->excludes(status);
  // Slurm (docs/cluster.md).
  auto* slurm = sub->add_flag("--slurm", st->slurm,
                              "Write OUT/slurm/study.sbatch, a Slurm job array over the runs not done, running or "
                              "queued (one run per task, or --array-tasks tasks dealt the runs), and exit")
                    ->excludes(list)
                    ->excludes(status)
                    ->excludes(reanalyse)
                    ->excludes(runList)
                    ->excludes(taskIndex)
                    ->excludes(taskCount)
                    ->excludes(jobs);
  study::SlurmOptions& so = st->slurmOptions;
  sub->add_flag("--submit", st->submit, "With --slurm: submit the script with sbatch and print the job id")
      ->needs(slurm);
  sub->add_option("--partition", so.partition, "With --slurm: the partition (#SBATCH --partition)")->needs(slurm);
  sub->add_option("--time", so.time, "With --slurm: each task's time limit, e.g. 2:00:00 or 1-12 (#SBATCH --time)")
      ->needs(slurm);
  sub->add_option("--mem", so.mem, "With --slurm: memory per node, e.g. 4G (#SBATCH --mem)")->needs(slurm);
  sub->add_option("--account", so.account, "With --slurm: the account charged (#SBATCH --account)")->needs(slurm);
  sub->add_option("--cpus-per-task", so.cpusPerTask,
                  "With --slurm: CPUs per task, and the runs each task runs at once (#SBATCH --cpus-per-task)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str()
      ->needs(slurm);
  sub->add_option("--array-limit", so.arrayLimit, "With --slurm: tasks running at once (#SBATCH --array=0-N%LIMIT)")
      ->check(CLI::Range(1, 1000000))
      ->needs(slurm);
  sub->add_option("--array-tasks", so.maxTasks,
                  "With --slurm: at most this many array tasks, runs dealt round-robin (default: one per run)")
      ->check(CLI::Range(1, 1000000))
      ->needs(slurm);
  sub->add_option("--sbatch-line", so.extraLines, "With --slurm: one more #SBATCH option, e.g. --qos=long (repeatable)")
      ->allow_extra_args(false)
      ->needs(slurm);
  sub->add_flag("--quiet,-q", st->quiet, "No progress lines");
  sub->add_option("--max-runs", st->maxRuns,
                  "Refuse a sweep file that lists more runs than this (a guard against a mistyped list or replicas)")
      ->check(unsignedInteger())
      ->capture_default_str();
  sub->callback([st] { runSweepCommand(*st); });
}

}  // namespace confpack::app
