// confpack-bench: nscd against Bullet on the same deposits, in one process. Writes bench.json
// (its shape in docs/performance.md, "The bench") and prints one line per case. With --micro it
// runs the Google Benchmark micro-benchmarks of the nscd phases instead (bench/microbench.hpp)
// and writes Google Benchmark's JSON report. Its own executable, so that the product binary
// carries neither Google Benchmark nor code that reaches into nscd's internals.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <memory>

#include "apps/cli_common.hpp"
#include "apps/progress.hpp"
#include "bench/bench.hpp"
#include "bench/microbench.hpp"
#include "core/packing_io.hpp"

namespace confpack::bench {

namespace {

using app::applyThreads;
using app::checkInput;
using app::nonNegativeNumber;
using app::positiveNumber;
using app::Progress;
using app::runWork;

struct BenchState {
  BenchDef def;
  std::vector<std::string> cases;
  std::filesystem::path out = "bench.json";
  bool quiet = false;
  bool micro = false;
  MicroBenchDef microDef;
  bool outGiven = false;
  std::filesystem::path dump;  ///< --micro-dump: write the pile's block there instead of timing
};

void runDumpCommand(const BenchState& st) {
  checkInput("", [&] { validatePileDump(st.microDef.pile, st.dump); });
  runWork("", [&] {
    dumpPileBlock(st.microDef.pile, st.dump);
    fmt::print("bench: wrote {}\n", st.dump.string());
  });
}

void runMicroCommand(BenchState& st) {
  if (!st.dump.empty()) return runDumpCommand(st);
  // The whole-run default name would mislabel a micro-benchmark report.
  if (!st.outGiven) st.out = "micro.json";
  checkInput("", [&] {
    st.microDef.seed = st.def.seed;
    validateMicroBench(st.microDef);
    if (std::filesystem::is_directory(st.out))
      throw std::invalid_argument(fmt::format("--out {} is a directory; give a file name", st.out.string()));
    const std::filesystem::path dir = st.out.has_parent_path() ? st.out.parent_path() : ".";
    if (!std::filesystem::is_directory(dir))
      throw std::invalid_argument(fmt::format("--out {}: directory {} does not exist", st.out.string(), dir.string()));
  });
  runWork("", [&] {
    const nlohmann::json targets = runMicroBench(st.microDef, st.out);
    for (const nlohmann::json& t : targets) fmt::print("bench: target {}\n", targetLine(t));
    fmt::print("bench: wrote {}\n", st.out.string());
  });
}

void runBenchCommand(BenchState& st) {
  if (st.micro) return runMicroCommand(st);
  checkInput("", [&] {
    if (!st.cases.empty()) st.def.cases = st.cases;
    for (const std::string& c : st.def.cases)
      if (std::find(benchCaseNames().begin(), benchCaseNames().end(), c) == benchCaseNames().end())
        throw std::invalid_argument(fmt::format("unknown case '{}' (expected msp-w10, mpp-w10, scaling or rest)", c));
    if (std::filesystem::is_directory(st.out))
      throw std::invalid_argument(fmt::format("--out {} is a directory; give a file name", st.out.string()));
  });
  runWork("", [&] {
    applyThreads(st.def.threads);
    // A full bench runs for hours: each compaction reports its progress (simulated time, steps,
    // iterations, equilibrium ratios) between the lines that say which case and backend ran.
    Progress progress("bench", !st.quiet, 30.0);
    const nlohmann::json result = runBench(
        st.def, [&](const std::string& line) { progress.note(line); },
        [&](double fraction, const std::string& status) { progress.update(fraction, status); });
    core::writeFileAtomically(st.out, result.dump(2));
    fmt::print("bench: wrote {}\n", st.out.string());
  });
}

/// The options of confpack-bench, on the program's own (root) command.
void addBenchOptions(CLI::App* sub, const std::shared_ptr<BenchState>& st) {
  auto* cases = sub->add_option("--case", st->cases,
                                "Cases to run: msp-w10, mpp-w10, scaling, rest (time to equilibrium against n, "
                                "nscd only) (default: msp-w10, mpp-w10, scaling)");
  sub->add_option("--out", st->out, "Output file (micro.json with --micro)")->capture_default_str();
  auto* timeLimit = sub->add_option("--time-limit", st->def.timeLimit, "Simulated time limit of each compaction [t0]")
                        ->check(positiveNumber())
                        ->capture_default_str();
  auto* scale =
      sub->add_option("--scale", st->def.scale, "Multiplies the box length and width (0.5 = a quarter of the grains)")
          ->check(positiveNumber())
          ->capture_default_str();
  auto* scalingSteps = sub->add_option("--scaling-steps", st->def.scalingSteps, "Steps timed per scaling point")
                           ->check(positiveNumber())
                           ->capture_default_str();
  auto* scalingFall =
      sub->add_option("--scaling-fall", st->def.scalingFall,
                      "Simulated time before the timed steps of a scaling point, for the pile to load [t0]")
          ->check(nonNegativeNumber())
          ->capture_default_str();
  auto* scalingSizes = sub->add_option("--scaling-sizes", st->def.scalingSizes, "Grain counts of the scaling series")
                           ->check(positiveNumber());
  auto* restSizes =
      sub->add_option("--rest-sizes", st->def.restSizes, "Grain counts of the rest series")->check(positiveNumber());
  sub->add_option("--seed", st->def.seed, "Seed of the deposits (and of the micro-benchmark poses)")
      ->capture_default_str();
  auto* threads =
      sub->add_option("--threads", st->def.threads, "Worker threads")->check(positiveNumber())->capture_default_str();
  auto* adaptive =
      sub->add_flag("--adaptive-dt", st->def.adaptiveDt,
                    "msp-w10, mpp-w10 and the rest series on the adaptive time step (as run --adaptive-dt)");
  auto* protocol = app::addProtocolOption(*sub, st->def.protocol);
  sub->add_flag("--quiet,-q", st->quiet, "No progress lines");
  auto* micro = sub->add_flag("--micro", st->micro,
                              "Run the Google Benchmark micro-benchmarks of the nscd phases instead (broad phase, "
                              "narrow phase per pair type, one Gauss-Seidel sweep)");
  // The whole-run options mean nothing to the micro-benchmarks (which time one core): refuse them
  // rather than ignore them.
  for (CLI::Option* o :
       {cases, timeLimit, scale, scalingSteps, scalingFall, scalingSizes, restSizes, threads, adaptive, protocol})
    micro->excludes(o);
  sub->add_option("--micro-filter", st->microDef.filter, "Regex selecting micro-benchmarks by name")
      ->needs(micro)
      ->capture_default_str();
  sub->add_option("--micro-pile", st->microDef.pile,
                  "With --micro: also time MPRGP's solve of this packing's step (MprgpSolve/sgs|cholesky/pile), e.g. "
                  "of a run stopped in its creep")
      ->needs(micro);
  auto* dump = sub->add_option("--micro-dump", st->dump,
                               "With --micro-pile: write that pile's step (rows.csv, bodies.csv, block.json with "
                               "MPRGP's solution) into this new folder instead of timing, for other solvers to try");
  dump->needs(sub->get_option("--micro-pile"));
  sub->add_option("--micro-repetitions", st->microDef.repetitions,
                  "Repetitions of each micro-benchmark (reported: mean, median, stddev, cv)")
      ->needs(micro)
      ->check(positiveNumber())
      ->capture_default_str();
  sub->add_option("--micro-min-time", st->microDef.minTime, "Minimum timed duration of one repetition [s]")
      ->needs(micro)
      ->check(positiveNumber())
      ->capture_default_str();
  // A dump times nothing: the timing options would be ignored, so they are refused.
  for (const char* name : {"--out", "--micro-filter", "--micro-repetitions", "--micro-min-time"})
    dump->excludes(sub->get_option(name));
  sub->callback([st, sub] {
    st->outGiven = sub->count("--out") > 0;
    runBenchCommand(*st);
  });
}

}  // namespace

}  // namespace confpack::bench

int main(int argc, char** argv) {
  CLI::App app{
      "confpack-bench: time nscd against Bullet on the same packings (bench.json), or with --micro the nscd "
      "phases alone (Google Benchmark, micro.json)"};
  app.name("confpack-bench");
  app.failure_message(confpack::app::oneLineFailure);
  confpack::bench::addBenchOptions(&app, std::make_shared<confpack::bench::BenchState>());
  return confpack::app::parseAndRun(app, argc, argv);
}
