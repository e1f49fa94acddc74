// `confpack sweep FILE`: runs a study described by a sweep file (docs/sweeps.md), resumably, in
// parallel (--jobs) or as one slice of a cluster job array (--task-index/--task-count).
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <memory>

#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "backends/backend_factory.hpp"
#include "study/sweep.hpp"
#include "study/run_pipeline.hpp"
#include "study/sweep_runner.hpp"

namespace confpack::app {

namespace {

struct SweepState {
  std::filesystem::path file;
  std::filesystem::path out;
  int jobs = 1;
  int threads = 0;
  std::size_t taskIndex = 0;
  std::size_t taskCount = 1;
  bool list = false;
  bool quiet = false;
  std::size_t maxRuns = study::kDefaultMaxRuns;
};

void runSweepCommand(const SweepState& st) {
  study::SweepSpec spec;
  std::vector<study::SweepRun> runs;
  std::filesystem::path out = st.out.empty() ? std::filesystem::path(st.file.stem()) : st.out;
  checkInput("sweep", [&] {
    spec = study::readSweepSpec(st.file, st.maxRuns);
    runs = study::expandRuns(spec);
    study::sliceRuns(runs, st.taskIndex, st.taskCount);  // validates the slice
    // The sweep file leaves backend_options to the backend: checked here, so that a typo is bad
    // input (exit 2) rather than a failure of every run.
    const std::vector<std::string> varied = study::variedSettings(runs);
    for (const study::SweepRun& run : runs) {
      try {
        backends::checkBackendOptions(run.config.backend, run.config.backendOptions);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(fmt::format("{}: run {} ({}): backend_options: {}", st.file.string(), run.name,
                                                run.label(varied), e.what()));
      }
      try {
        study::checkRunCells(run.config, run.config.estimatedGrainCount());
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(
            fmt::format("{}: run {} ({}): {}", st.file.string(), run.name, run.label(varied), e.what()));
      }
    }
    if (st.jobs < 1) throw std::invalid_argument(fmt::format("--jobs must be >= 1 (got {})", st.jobs));
    checkOutputTarget(out);
  });
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
    opt.quiet = st.quiet;
    opt.live = ::isatty(STDERR_FILENO) != 0;
    summary = study::runSweep(spec, out, opt, study::pipelineRunner(st.threads), study::pipelineDepositor());
  });
  if (summary.failed > 0) {
    fmt::print(stderr, "confpack sweep: error: {} run(s) failed (see runs/*/failed.json); run the same command again to retry them\n",
               summary.failed);
    throw CLI::RuntimeError(kExitRuntimeFailure);
  }
  fmt::print("sweep {}: {} of {} runs in this task finished ({} now, {} earlier); report with: confpack report {}\n",
             spec.name, summary.ran + summary.alreadyDone, summary.inSlice, summary.ran, summary.alreadyDone,
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
  sub->add_option("file", st->file, "Sweep file (JSON, format confpack-sweep)")->required()->check(CLI::ExistingFile);
  sub->add_option("--out", st->out, "Sweep folder (default: the sweep file's name without extension)");
  sub->add_option("--jobs,-j", st->jobs, "Runs at the same time")->check(CLI::Range(1, 4096));
  sub->add_option("--threads", st->threads, "Threads per run (0: from the sweep file)")->check(CLI::Range(0, 4096));
  sub->add_option("--task-index", st->taskIndex, "This task's slice, 0-based (e.g. $SLURM_ARRAY_TASK_ID)");
  sub->add_option("--task-count", st->taskCount, "Number of tasks sharing the sweep (e.g. $SLURM_ARRAY_TASK_COUNT)")
      ->check(CLI::Range(1, 1000000));
  sub->add_flag("--list", st->list, "Print the run table (with each run's status when the folder exists) and exit");
  sub->add_flag("--quiet,-q", st->quiet, "No progress lines");
  sub->add_option("--max-runs", st->maxRuns,
                  "Refuse a sweep file that lists more runs than this (a guard against a mistyped list or replicas)")
      ->check(unsignedInteger())
      ->capture_default_str();
  sub->callback([st] { runSweepCommand(*st); });
}

}  // namespace confpack::app
