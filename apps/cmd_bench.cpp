// `confpack bench`: nscd against Bullet on the same deposits, in one process (issue 7).
// Writes bench.json (shape in the README's performance section) and prints one line per case.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <memory>

#include "apps/bench.hpp"
#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "core/packing_io.hpp"

namespace confpack::app {

namespace {

struct BenchState {
  BenchDef def;
  std::vector<std::string> cases;
  std::filesystem::path out = "bench.json";
  bool quiet = false;
};

void runBenchCommand(BenchState& st) {
  checkInput("bench", [&] {
    if (!st.cases.empty()) st.def.cases = st.cases;
    for (const std::string& c : st.def.cases)
      if (std::find(benchCaseNames().begin(), benchCaseNames().end(), c) == benchCaseNames().end())
        throw std::invalid_argument(fmt::format("unknown case '{}' (expected msp-w10, mpp-w10 or scaling)", c));
    if (std::filesystem::is_directory(st.out))
      throw std::invalid_argument(fmt::format("--out {} is a directory; give a file name", st.out.string()));
  });
  runWork("bench", [&] {
    applyThreads(st.def.threads);
    const nlohmann::json result = runBench(st.def, [&](const std::string& line) {
      if (!st.quiet) fmt::print(stderr, "bench: {}\n", line);
    });
    core::writeFileAtomically(st.out, result.dump(2));
    fmt::print("bench: wrote {}\n", st.out.string());
  });
}

}  // namespace

void registerBench(CLI::App& app) {
  auto st = std::make_shared<BenchState>();
  auto* sub = app.add_subcommand("bench", "Time nscd against Bullet on the same packings; writes bench.json");
  sub->add_option("--case", st->cases, "Cases to run: msp-w10, mpp-w10, scaling (default: all)");
  sub->add_option("--out", st->out, "Output file")->capture_default_str();
  sub->add_option("--time-limit", st->def.timeLimit, "Simulated time limit of each compaction [t0]")
      ->check(positiveNumber())
      ->capture_default_str();
  sub->add_option("--scale", st->def.scale, "Multiplies the box length and width (0.5 = a quarter of the grains)")
      ->check(positiveNumber())
      ->capture_default_str();
  sub->add_option("--scaling-steps", st->def.scalingSteps, "Steps timed per scaling point")
      ->check(positiveNumber())
      ->capture_default_str();
  sub->add_option("--scaling-sizes", st->def.scalingSizes, "Grain counts of the scaling series")
      ->check(positiveNumber());
  sub->add_option("--seed", st->def.seed, "Seed of the deposits")->capture_default_str();
  sub->add_option("--threads", st->def.threads, "Worker threads")->check(positiveNumber())->capture_default_str();
  sub->add_flag("--quiet,-q", st->quiet, "No progress lines");
  sub->callback([st] { runBenchCommand(*st); });
}

}  // namespace confpack::app
