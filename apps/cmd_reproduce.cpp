// `confpack reproduce --scale tiny|quick|medium|paper --out DIR`: runs the confinement study
// (docs/model.md, "The study and its report"; study/reproduce.hpp)
// into DIR (a resumable sweep folder) and writes its report into DIR/report/.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <memory>
#include <thread>

#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "core/packing_io.hpp"
#include "study/report.hpp"
#include "study/reproduce.hpp"
#include "study/sweep.hpp"
#include "study/sweep_runner.hpp"

namespace confpack::app {

namespace {

struct ReproduceState {
  std::string scale = "quick";
  std::filesystem::path out;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool list = false;
  bool quiet = false;
};

void runReproduceCommand(const ReproduceState& st) {
  study::SweepSpec spec;
  std::vector<study::SweepRun> runs;
  checkInput("reproduce", [&] {
    spec = study::parseSweepSpec(study::reproductionSweep(st.scale), st.scale);
    runs = study::expandRuns(spec);
    // A study folder (it holds the run table) is confpack's, marked or not: rerunning resumes it.
    if (!std::filesystem::exists(st.out / study::kSweepTable)) checkOutputTarget(st.out);
  });
  if (st.list) {
    std::fputs(study::formatRunTable(
                   runs, std::filesystem::exists(st.out / study::kSweepTable) ? st.out : std::filesystem::path{})
                   .c_str(),
               stdout);
    return;
  }
  study::SweepSummary summary;
  study::ReportSummary report;
  runWork("reproduce", [&] {
    WorkStep step("running the study");
    study::SweepOptions opt;
    opt.jobs = st.jobs;
    opt.quiet = st.quiet;
    opt.live = ::isatty(STDERR_FILENO) != 0;
    markOutputFolder(st.out);
    // The study's definition next to its results, as a sweep file a user can edit and rerun.
    core::writeFileAtomically(st.out / "study.json", study::reproductionSweep(st.scale).dump(2));
    summary = study::runSweep(spec, st.out, opt,
                              study::pipelineRunner(1, compaction::Checkpointing{}.everySeconds, spec.settleWith),
                              study::pipelineDepositor());
    step.next("writing the report");
    // Staged like `confpack report`'s: an interrupted report leaves the previous one whole.
    StagedOutput staged(st.out / "report");
    report = study::writeReport(st.out, staged.dir());
    step.next("moving the report into place");
    staged.commit();
    report.html = st.out / "report" / report.html.filename();
    report.markdown = st.out / "report" / report.markdown.filename();
  });
  fmt::print("reproduce {}: {} runs ({} finished now, {} earlier, {} failed) in {:.0f} s\nreport: {}\n        {}\n",
             st.scale, summary.total, summary.ran, summary.alreadyDone, summary.failed, summary.wallSeconds,
             report.html.string(), report.markdown.string());
  if (summary.failed > 0) {
    fmt::print(stderr,
               "confpack reproduce: error: {} run(s) failed (listed in the report); run the same command "
               "again to retry them\n",
               summary.failed);
    throw CLI::RuntimeError(kExitRuntimeFailure);
  }
}

}  // namespace

void registerReproduce(CLI::App& app) {
  auto st = std::make_shared<ReproduceState>();
  auto* sub = app.add_subcommand(
      "reproduce",
      "Run the confinement study (docs/model.md) with both backends and write its report (DIR/report/report.html). "
      "Rerunning the same command resumes an interrupted study.");
  sub->add_option(
         "--scale", st->scale,
         "tiny (smoke test, minutes), quick (shrunk box, about 10 min on 2 cores), medium (830 to 4,300 "
         "monodisperse grains a run, meant to run overnight on 2 cores) or paper (the paper's sizes, for a cluster)")
      ->check(CLI::IsMember({"tiny", "quick", "medium", "paper"}))
      ->capture_default_str();
  sub->add_option("--out", st->out, "Study folder (sweep runs, deposits, report/)")->required();
  sub->add_option("--jobs,-j", st->jobs, "Runs at the same time")->check(CLI::Range(1, 4096))->capture_default_str();
  sub->add_flag("--list", st->list, "Print the run table and exit");
  sub->add_flag("--quiet,-q", st->quiet, "No progress lines");
  sub->callback([st] { runReproduceCommand(*st); });
}

}  // namespace confpack::app
