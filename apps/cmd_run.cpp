// `confpack run`: the whole protocol (docs/model.md, "Protocols") for one configuration and one
// backend: deposit (or, with --from, the grains of a packing file), compact until equilibrium or
// the time limit, analyse, write.
//
//   DIR/result.json    docs/model.md, "Results" (written last: its presence means the run finished)
//   DIR/packing.json   final packing with contacts and forces (docs/packing-format.md)
//   DIR/config.json    the fully resolved RunConfig: the time step taken and the backend's
//                      resolved settings as its backend_options, so that `confpack run --config
//                      DIR/config.json` (with --from the same packing, for a run from one)
//                      reruns it
//   DIR/*.csv          profiles
//   DIR/vtk/           ParaView frames (frame_grains.pvd, frame_contacts.pvd)
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <memory>
#include <optional>
#include <stdexcept>

#include "analysis/plausibility.hpp"
#include "apps/cli_common.hpp"
#include "apps/commands.hpp"
#include "apps/progress.hpp"
#include "backends/backend_factory.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "core/settings_table.hpp"
#include "study/run_pipeline.hpp"

namespace confpack::app {

namespace {

/// A result number for the summary line; "n/a" when it does not apply (null), e.g. an empty bulk.
std::string number(const nlohmann::json& v, const char* format = "{:.4f}") {
  return v.is_number() ? fmt::format(fmt::runtime(format), v.get<double>()) : std::string("n/a");
}

struct RunState {
  core::RunConfig cfg;
  CommonOptions opts;
  std::string backendOptions;               ///< --backend-options JSON text
  std::string compactionOptions;            ///< --compaction-options JSON text
  std::string from;                         ///< --from PACKING: start from its grains instead of a deposit
  std::string configFile;                   ///< --config FILE: the configuration instead of the flags
  bool allowImplausible = false;            ///< --allow-implausible: take an implausible --from packing
  compaction::Checkpointing checkpointing;  ///< --checkpoint FILE, --checkpoint-every SECONDS
  CLI::App* sub = nullptr;
};

/// Options that --from replaces: the packing gives the box and the grains.
constexpr const char* kGivenByPacking[] = {"--length-x",   "--width",          "--periodic-y", "--height",
                                           "--shape",      "--small-fraction", "--grains",     "--pinacoid-G",
                                           "--pinacoid-E", "--pinacoid-alpha"};

/// Flags that --config may go with: they set nothing the configuration holds.
constexpr const char* kBesideConfig[] = {"--help",       "--config",           "--out",
                                         "--quiet",      "--verbose",          "--from",
                                         "--checkpoint", "--checkpoint-every", "--allow-implausible"};

/// The configuration of `run --config FILE` (config.json of a run, or part of one: missing keys
/// take their defaults), read by the RunConfig reader. The file holds the whole configuration: a
/// flag that sets part of it is refused rather than silently merged.
core::RunConfig readConfigFile(const RunState& st) {
  for (const CLI::Option* option : st.sub->get_options()) {
    const std::string name = option->get_name();
    if (option->count() > 0 &&
        std::find(std::begin(kBesideConfig), std::end(kBesideConfig), name) == std::end(kBesideConfig))
      throw std::invalid_argument(
          fmt::format("--config gives the whole configuration; drop {} (or change it in the file)", name));
  }
  const nlohmann::json j = core::readJsonFile(st.configFile, "run configuration");
  try {
    return j.get<core::RunConfig>();
  } catch (const std::exception& e) {
    throw std::invalid_argument(fmt::format("{}: {}", st.configFile, e.what()));
  }
}

/// config.json of a finished run: `cfg` with what the run resolved, the time step it took and the
/// backend's settings (every key, the defaults included) as backend_options, so that the same
/// reader takes it back and the rerun does not depend on this version's defaults.
nlohmann::json resolvedConfig(core::RunConfig cfg, const nlohmann::json& result) {
  cfg.compaction.dt = result["config"]["compaction"]["dt"].get<double>();
  cfg.backendOptions = result["config"]["backend_settings"];
  return cfg;
}

/// The starting state of `run --from`: the packing's grains at rest, with cfg's box and population
/// taken from it (the side walls' friction from --wall-friction or --config when given).
compaction::Deposit startFromPacking(RunState& st) {
  for (const char* name : kGivenByPacking)
    if (st.sub->count(name) > 0)
      throw std::invalid_argument(fmt::format("--from takes the box and the grains from the packing; drop {}", name));
  const core::Packing packing = core::readPacking(st.from);
  analysis::checkPlausible(packing, st.from, st.allowImplausible);
  core::RunConfig& cfg = st.cfg;
  const bool frictionGiven = st.sub->count("--wall-friction") > 0 || !st.configFile.empty();
  cfg.box = packing.box;
  if (!frictionGiven) cfg.walls = packing.walls;
  compaction::Deposit start = compaction::depositFromPacking(packing, st.from);
  cfg.population.shape = packing.grains.front().shape;
  if (cfg.population.shape == core::ShapeKind::Pinacoid) cfg.population.pinacoid = packing.grains.front().params;
  cfg.population.largeSize = 0.0;
  for (const core::Grain& g : packing.grains) cfg.population.largeSize = std::max(cfg.population.largeSize, g.size);
  cfg.deposition.grainCount = packing.grains.size();
  return start;
}

void runRun(RunState& st) {
  core::RunConfig& cfg = st.cfg;
  std::optional<compaction::Deposit> start;
  checkInput("run", [&] {
    if (!st.configFile.empty()) cfg = readConfigFile(st);
    if (!st.backendOptions.empty()) cfg.backendOptions = core::parseJsonText(st.backendOptions, "--backend-options");
    // After the flags: a key given both ways takes the JSON's value.
    if (!st.compactionOptions.empty())
      core::compactionTable().read(core::parseJsonText(st.compactionOptions, "--compaction-options"), cfg.compaction);
    if (!st.from.empty()) {
      const WorkStep step("reading the packing file");
      start = startFromPacking(st);
    }
    if (!start) cfg.fitLengthToGrainCap();  // a packing brings its own box
    cfg.validate();
    if (!start) cfg.validateDeposit();
    study::checkRunCells(cfg, start ? static_cast<double>(start->grains.size()) : cfg.estimatedGrainCount());
    // Here, not when the backend is built: an unknown key is bad input (exit 2), as bad JSON is.
    backends::checkBackendOptions(cfg.backend, cfg.backendOptions);
    checkOutputTarget(st.opts.out);
    const std::filesystem::path& file = st.checkpointing.file;
    if (!file.empty() && std::filesystem::is_directory(file))
      throw std::invalid_argument(fmt::format("--checkpoint {}: is a folder; give the file to write", file.string()));
  });
  runWork("run", [&] {
    applyThreads(cfg.threads);
    StagedOutput output(st.opts.out);
    Progress progress("run", !st.opts.quiet, 10.0);
    WorkStep step("compacting, analysing and writing the run");
    const nlohmann::json result = study::runAndWrite(
        cfg, output.dir(), [&](double fraction, const std::string& status) { progress.update(fraction, status); },
        start ? &*start : nullptr, st.checkpointing);
    progress.done(result["equilibrium"]["reached"].get<bool>() ? "equilibrium reached" : "time limit reached");
    step.next("writing config.json");
    writeJson(output.dir() / "config.json", resolvedConfig(cfg, result));
    step.next("moving the output into place");
    output.commit();
    fmt::print(
        "run: {} {} grains, phi = {}, Z = {}, interpenetration {} %, equilibrium {} ({} steps, {:.1f} s) -> {}\n",
        cfg.backend, result["n_grains"].get<int>(), number(result["solid_fraction"]),
        number(result["coordination"]["Z"], "{:.3f}"), number(result["interpenetration_percent"]["exact"], "{:.2e}"),
        result["equilibrium"]["reached"].get<bool>() ? "reached" : "NOT reached", result["timing"]["steps"].get<long>(),
        result["timing"]["wall_s"].get<double>(), output.target().string());
  });
}

}  // namespace

void registerRun(CLI::App& app) {
  auto st = std::make_shared<RunState>();
  auto* sub = st->sub = app.add_subcommand(
      "run", "Deposit, compact with a backend until equilibrium (or the time limit), analyse, write DIR/result.json");
  addRunConfigOptions(*sub, st->cfg, st->opts);
  sub->add_option("--dt", st->cfg.compaction.dt,
                  "Time step [t0]; 0 = the fixed step from the deposit's drop, else in [1e-06, 0.1] (docs/model.md, "
                  "\"Time step\")")
      ->check(realIn(0.0, core::kMaxTimeStep, false, false, "0 or a time step of at most 0.1 t0", "T0"))
      ->capture_default_str();
  sub->add_flag("--adaptive-dt", st->cfg.compaction.adaptiveDt,
                "Adaptive time step: the largest that keeps every grain within a hundredth of the smallest "
                "grain's size of motion per step at its current speed, never below --dt (or the fixed "
                "step), growing at most 1.25x per step; "
                "equilibrium is then also checked every 0.5 t0");
  addProtocolOption(*sub, st->cfg.compaction.protocol);
  sub->add_option("--switch-kinetic-ratio", st->cfg.compaction.switchKineticRatio,
                  "quasi-static: hand over to the finisher at the first check whose mean kinetic ratio "
                  "E_k / (d^3 P) over the grains is below this")
      ->check(positiveNumber())
      ->capture_default_str();
  sub->add_option("--fall-time-limit", st->cfg.compaction.fallTimeLimit,
                  "quasi-static: the longest fall before the finisher takes over [t0]; 0 = --time-limit")
      ->check(nonNegativeNumber())
      ->capture_default_str();
  sub->add_option("--time-limit", st->cfg.compaction.timeLimit,
                  "Simulated time after which the run stops, reported as not equilibrated [t0]")
      ->check(positiveNumber())
      ->capture_default_str();
  sub->add_option("--check-interval", st->cfg.compaction.checkInterval, "Steps between equilibrium checks")
      ->check(positiveNumber())
      ->capture_default_str();
  sub->add_option("--frame-interval", st->cfg.compaction.frameInterval,
                  "Steps between ParaView frames (0 = first and last only)")
      ->check(nonNegativeNumber())
      ->capture_default_str();
  sub->add_option("--grains", st->cfg.deposition.grainCount,
                  "Number of grains (0 = from --height and the expected solid fraction)")
      ->capture_default_str();
  sub->add_option("--from", st->from,
                  "Start from the grains of this packing file (their poses, at rest) instead of a new deposit, "
                  "e.g. to take a run that stopped before equilibrium on to rest; the box and the grains come "
                  "from the file")
      ->type_name("PACKING");
  addAllowImplausibleFlag(*sub, st->allowImplausible);
  sub->add_option("--config", st->configFile,
                  "Take the whole configuration from this file, e.g. DIR/config.json of an earlier run to rerun it "
                  "(missing keys take their defaults; goes with --out, --quiet, --verbose and --from only)")
      ->type_name("FILE");
  sub->add_option("--checkpoint", st->checkpointing.file,
                  "Save the run's state in FILE as it goes and resume from FILE when it holds this run's state: a "
                  "run stopped by a time limit, SIGTERM or a dead machine goes on where it stood (docs/model.md, "
                  "\"Checkpoints\"); removed when the run is done")
      ->type_name("FILE");
  sub->add_option("--checkpoint-every", st->checkpointing.everySeconds,
                  "With --checkpoint: save at the first equilibrium check after this many seconds of wall time "
                  "(and when SIGINT or SIGTERM stops the run)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str()
      ->type_name("SECONDS");
  sub->add_option("--backend-options", st->backendOptions,
                  "Backend settings as JSON, e.g. '{\"tolerance\": 1e-5}' (see the README for the keys)");
  sub->add_option("--compaction-options", st->compactionOptions,
                  "Compaction settings as JSON, e.g. '{\"trust_radius\": 0.02}' (`confpack options` lists the keys)");
  sub->callback([st] { runRun(*st); });
}

}  // namespace confpack::app
