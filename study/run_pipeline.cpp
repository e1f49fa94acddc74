#include "study/run_pipeline.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "analysis/equilibrium.hpp"
#include "analysis/interpenetration.hpp"
#include "backends/backend_factory.hpp"
#include "core/build_info.hpp"
#include "core/interrupt.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "core/quasi_static_finisher.hpp"
#include "core/vtk_writer.hpp"

namespace confpack::study {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// CPU time of the whole process (every thread) [s]: unlike the wall clock, it does not count the
/// time other jobs on a shared machine take from this one.
double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// The packing as the backend has it now: poses from the states, contacts of the last step.
core::Packing snapshot(const core::RunConfig& cfg, const std::vector<core::Grain>& grains,
                       const core::ContactBackend& backend) {
  core::Packing p;
  p.box = cfg.box;
  p.walls = cfg.walls;
  p.grains = grains;
  const auto& states = backend.states();
  for (std::size_t i = 0; i < grains.size(); ++i) {
    p.grains[i].position = states[i].position;
    p.grains[i].orientation = states[i].orientation;
  }
  p.contacts = backend.contacts();
  return p;
}

std::vector<core::Vec3> velocities(const std::vector<core::BodyState>& states) {
  std::vector<core::Vec3> v;
  v.reserve(states.size());
  for (const auto& s : states) v.push_back(s.velocity);
  return v;
}

}  // namespace

AdaptiveTimeStep::AdaptiveTimeStep(const std::vector<core::Grain>& grains, double gravity, double floor)
    : gravity_(gravity), floor_(floor) {
  // Counting a sphere's spin held the step of a 1,648-sphere pile with mu_w = 0.5 at a third of
  // its value without friction.
  spinLever_.reserve(grains.size());
  for (const core::Grain& g : grains) spinLever_.push_back(g.spinLever());
  motion_ = 0.01 * core::smallestSize(grains);
}

double AdaptiveTimeStep::next(double previous, const std::vector<core::BodyState>& states) const {
  if (spinLever_.empty()) return floor_;
  double v = 0.0;
  for (std::size_t i = 0; i < spinLever_.size(); ++i)
    v = std::max(v, states[i].velocity.norm() + states[i].angularVelocity.norm() * spinLever_[i]);
  // v dt + g dt^2 / 2 = s: the positive root, in the form that does not cancel when v^2 >> 2 g s.
  const double dt = 2.0 * motion_ / (v + std::sqrt(v * v + 2.0 * gravity_ * motion_));
  return std::max(floor_, std::min(dt, kAdaptiveGrowth * previous));
}

analysis::AnalysisOptions analysisOptions() {
  analysis::AnalysisOptions o;
  o.equilibrium = false;  // the pipeline has the velocities: it writes its own block
  return o;
}

void checkRunCells(const core::RunConfig& cfg, double grains) {
  analysis::checkCells(cfg.box, grains, analysisOptions(),
                       "a run analyses with the default slices and cells: make the box smaller");
}

double defaultTimeStep(const core::RunConfig& cfg, const core::Deposit& deposit) {
  const double volume = core::totalVolume(deposit.grains);
  const double finalHeight = volume / (cfg.box.lengthX * cfg.box.width * cfg.deposition.expectedSolidFraction);
  const double dh = std::max(deposit.pileHeight - finalHeight, cfg.population.largeSize);
  return 0.01 * std::sqrt(cfg.population.largeSize / (2.0 * dh));
}

core::Deposit depositFromPacking(const core::Packing& packing, const std::filesystem::path& source) {
  if (packing.grains.empty()) throw std::invalid_argument(fmt::format("{}: the packing has no grains", source.string()));
  core::Deposit d;
  d.grains = packing.grains;
  for (const core::Grain& g : d.grains) d.pileHeight = std::max(d.pileHeight, g.position.z() + g.boundingRadius());
  d.solidFraction = core::totalVolume(d.grains) / (packing.box.lengthX * packing.box.width * d.pileHeight);
  d.source = source.string();
  return d;
}

CompactionOutcome compact(const core::RunConfig& cfg, const core::Deposit& deposit, const std::filesystem::path& vtkDir,
                          const RunProgressFn& progress, const Checkpointing& checkpointing) {
  const auto start = Clock::now();
  const core::CompactionDef& def = cfg.compaction;
  // A checkpoint of this run, if there is one: the backend is then built at its poses.
  const nlohmann::json identity = checkpointing.file.empty() ? nlohmann::json() : checkpointIdentity(cfg, deposit);
  std::string ignoredWhy;
  std::optional<LoadedCheckpoint> resumed;
  if (!checkpointing.file.empty()) resumed = readCheckpoint(checkpointing.file, identity, ignoredWhy);
  core::SystemDef system;
  system.box = cfg.box;
  system.walls = cfg.walls;
  system.grains = deposit.grains;
  system.threads = cfg.threads;
  const auto makeBackend = [&] {
    return backends::makeBackend(cfg.backend, system,
                                 cfg.backendOptions.is_null() ? nlohmann::json::object() : cfg.backendOptions);
  };
  std::unique_ptr<core::ContactBackend> backend;
  // The finisher's first step is the last dynamic one; it is made when the fall ends, or here for
  // a run resumed in its finisher.
  std::optional<core::QuasiStaticFinisher> finish;
  const auto makeFinisher = [&](double firstStep) {
    finish.emplace(def, core::smallestSize(deposit.grains), firstStep);
  };
  if (resumed) {
    try {
      const std::vector<core::BodyState> saved =
          core::bodyStatesFromJson(resumed->backend.value("grains", nlohmann::json()), deposit.grains.size());
      for (std::size_t i = 0; i < saved.size(); ++i) {
        system.grains[i].position = saved[i].position;
        system.grains[i].orientation = saved[i].orientation;
      }
      if (resumed->counters.finisherStage) {
        makeFinisher(resumed->counters.dt);
        finish->restoreState(resumed->finisher);
      }
      backend = makeBackend();
      backend->restoreState(resumed->backend);
    } catch (const std::exception& e) {
      ignoredWhy = fmt::format("its state does not fit ({})", e.what());
      resumed.reset();
      backend.reset();
      finish.reset();
      system.grains = deposit.grains;
    }
  }
  if (!backend) backend = makeBackend();

  CompactionOutcome out;
  out.dt = def.dt > 0.0 ? def.dt : defaultTimeStep(cfg, deposit);
  const bool adaptive = def.adaptiveDt;
  // Bullet has no finisher: its runs stay dynamic, and result.json says which protocol ran.
  const bool finisher = def.protocol == core::Protocol::QuasiStatic && backend->hasQuasiStaticStep();
  if (finisher) backend->startQuasiStaticFall();
  // With the finisher, the dynamic steps are the fall, bounded by fall_time_limit when given.
  const bool fallBounded = finisher && def.fallTimeLimit > 0.0;
  const double timeLimit = fallBounded ? def.fallTimeLimit : def.timeLimit;
  out.protocol = finisher ? core::Protocol::QuasiStatic : core::Protocol::Dynamic;
  // A fixed step runs ceil(limit / dt) steps, its time counted as steps x dt (no round-off drift);
  // an adaptive one sums its steps until the sum reaches the limit.
  // A step count a long holds exactly (time_limit is bounded by validation; a tiny --dt is not).
  const double stepsToLimit = std::ceil(timeLimit / out.dt);
  if (!(stepsToLimit < 0x1p53))
    throw std::invalid_argument(fmt::format("compaction: time_limit {:g} t0 at dt {:g} t0 is more steps than can be counted",
                                            timeLimit, out.dt));
  const long maxSteps = static_cast<long>(stepsToLimit);
  const AdaptiveTimeStep adaptiveStep(deposit.grains, system.gravity.norm(), out.dt);
  // Where the compaction stands; a resumed run takes it over from its checkpoint.
  CompactionCounters c;
  c.dt = out.dt;
  c.dtLargest = out.dt;
  if (resumed) {
    c = resumed->counters;
    ++c.resumes;
  }
  const auto elapsed = [&] { return c.elapsedSeconds + secondsSince(start); };
  auto lastSave = Clock::now();
  const auto save = [&] {
    CompactionCounters now = c;
    now.elapsedSeconds = elapsed();
    writeCheckpoint(checkpointing.file, identity, now, backend->saveState(),
                    finish ? finish->saveState() : nlohmann::json());
    lastSave = Clock::now();
  };
  // At the top of a step: a stop signal saves the state before the run gives up, and so does the
  // first check after every checkpointing.everySeconds.
  const auto stopIfAsked = [&](const std::string& where) {
    if (core::stopSignal() == 0) return;
    if (checkpointing.file.empty()) throw core::Interrupted(core::stopSignal(), where);
    save();
    throw core::Interrupted(core::stopSignal(), fmt::format("{}; its state is saved in {}; the same command resumes it",
                                                            where, checkpointing.file.string()));
  };
  const auto saveIfDue = [&] {
    if (!checkpointing.file.empty() && secondsSince(lastSave) >= checkpointing.everySeconds) save();
  };

  std::optional<core::VtkSeries> frames;
  if (!vtkDir.empty()) {
    frames.emplace(vtkDir, "frame");
    core::Packing initial{cfg.box, cfg.walls, deposit.grains, std::nullopt};
    frames->addFrame(0.0, initial);
  }

  analysis::EquilibriumReport eq;
  bool haveEq = false;
  // One step of either stage: time it and add its profile to the totals.
  auto timed = [&](auto&& stepFn) {
    const Clock::time_point stepStart = Clock::now();
    const double cpuStart = processCpuSeconds();
    stepFn();
    c.stepSeconds += secondsSince(stepStart);
    c.stepCpuSeconds += processCpuSeconds() - cpuStart;
    ++c.steps;
    const core::StepProfile& prof = backend->profile();
    for (std::size_t k = 0; k < c.phaseSeconds.size(); ++k) c.phaseSeconds[k] += prof.seconds[k];
    c.iterations += prof.iterations;
    c.rowUpdates += static_cast<double>(prof.contactPoints) * prof.iterations;
  };
  // The equilibrium test (docs/model.md, "Equilibrium") of the state now, recorded in the history
  // and reported as progress.
  auto check = [&](const core::Packing& now, double fraction, const std::string& stage) {
    eq = analysis::equilibrium(now, backend->states(), system.gravity, system.density, def.forceRatio,
                               def.momentRatio, def.kineticRatio);
    haveEq = true;
    analysis::InterpenetrationDef exactOnly;
    exactOnly.lattice = false;  // the lattice bounds are for the final state only (costly)
    const double overlap = analysis::interpenetration(now, analysis::bulkRegion(now), exactOnly).exactPercent;
    c.history.push_back({c.steps, c.simTime, elapsed(), eq.maxForceRatio, eq.maxMomentRatio, eq.maxKineticRatio,
                         overlap, c.iterations, c.rowUpdates, c.phaseSeconds[static_cast<int>(core::Phase::Solve)],
                         c.stepSeconds, c.stepCpuSeconds});
    if (progress)
      progress(fraction, fmt::format("{} {} step {} iterations/step {:.1f} force {:.1e} moment {:.1e} kinetic {:.1e}",
                                     backend->name(), stage, c.steps, static_cast<double>(c.iterations) / c.steps,
                                     eq.maxForceRatio, eq.maxMomentRatio, eq.maxKineticRatio));
  };

  // Stage 1: time steps, until equilibrium, the time limit, or (quasi-static protocol) the end of
  // the fall.
  bool handOver = c.finisherStage;
  while (!c.finisherStage && (adaptive ? c.simTime < timeLimit : c.steps < maxSteps)) {
    stopIfAsked(fmt::format("at t = {:.3g} (step {})", c.simTime, c.steps));
    if (adaptive && c.steps > 0) {
      c.dt = adaptiveStep.next(c.dt, backend->states());
      c.dtLargest = std::max(c.dtLargest, c.dt);
    }
    timed([&] { backend->step(c.dt); });
    c.simTime = adaptive ? c.simTime + c.dt : static_cast<double>(c.steps) * out.dt;
    const bool lastStep = adaptive ? c.simTime >= timeLimit : c.steps == maxSteps;

    const bool frameDue = frames && def.frameInterval > 0 && c.steps % def.frameInterval == 0;
    const bool checkDue = c.steps % def.checkInterval == 0 || lastStep ||
                          (adaptive && c.simTime - c.lastCheckTime >= kAdaptiveCheckSpacing);
    if (!frameDue && !checkDue) continue;
    const core::Packing now = snapshot(cfg, deposit.grains, *backend);
    if (frameDue) frames->addFrame(c.simTime, now, velocities(backend->states()));
    if (checkDue) {
      c.lastCheckTime = c.simTime;
      check(now, std::min(1.0, c.simTime / timeLimit),
            fmt::format("t={:.1f}{}", c.simTime, adaptive ? fmt::format(" dt {:.1e}", c.dt) : ""));
      if (eq.reached) break;
      if (finisher && eq.meanSettlingKineticRatio < def.switchKineticRatio) {
        handOver = true;
        c.handOverAt = "switch_kinetic_ratio";
        break;
      }
      if (!lastStep) saveIfDue();
    }
  }
  // The quasi-static protocol's dynamic stage ends at the time limit too: the finisher takes over
  // from there, bounded by its own step count. handOverAt says which ended the fall; how far the
  // fall had got shows a pile the finisher (meant for the creep after the fall, docs/model.md)
  // was handed while still falling.
  if (!c.finisherStage) {
    if (finisher && !handOver && !eq.reached) {
      handOver = true;
      c.handOverAt = fallBounded ? "fall_time_limit" : "time_limit";
    }
    c.handOverKineticRatio = haveEq ? eq.meanSettlingKineticRatio : 0.0;
    c.dynamicSteps = c.steps;
    c.dynamicIterations = c.iterations;
    c.dynamicWallSeconds = elapsed();
    c.finisherStage = handOver;
    if (handOver) makeFinisher(c.dt);
  }

  // Stage 2 (quasi-static protocol): the finisher's steps from rest
  // (core/quasi_static_finisher.hpp). The equilibrium test is checked after each step that moved
  // nothing more than the settle tolerance (and every 20 steps, for the progress line); the
  // finisher stops once it holds there.
  if (handOver) {
    for (long k = finish->steps() + 1; k <= def.finisherMaxSteps; ++k) {
      stopIfAsked(fmt::format("in finisher step {} of the quasi-static protocol", k));
      timed([&] { finish->step(*backend); });
      const bool last = k == def.finisherMaxSteps;
      const bool frameDue = frames && def.frameInterval > 0 && c.steps % def.frameInterval == 0;
      if (!frameDue && !last && !finish->settled() && k % 20 != 0) continue;
      const core::Packing now = snapshot(cfg, deposit.grains, *backend);
      if (frameDue) frames->addFrame(c.simTime, now, velocities(backend->states()));
      check(now, static_cast<double>(k) / def.finisherMaxSteps,
            fmt::format("finisher {} h {:.1e} moved {:.1e}", k, finish->lastStepLength(),
                        finish->lastMove().maxDisplacement));
      if (eq.reached && finish->settled()) break;
      if (!last) saveIfDue();
    }
  }

  out.packing = snapshot(cfg, deposit.grains, *backend);
  out.states = backend->states();
  out.history = c.history;
  out.dtLargest = c.dtLargest;
  if (!haveEq)
    eq = analysis::equilibrium(out.packing, out.states, system.gravity, system.density, def.forceRatio,
                               def.momentRatio, def.kineticRatio);
  if (frames) {
    frames->addFrame(c.simTime, out.packing, velocities(out.states));
    frames->finish();
  }
  // With the finisher, equilibrium also needs its last step to have moved (almost) nothing: its
  // steps are so long that the force and kinetic ratios of a step say little about motion.
  out.reached = eq.reached && (!handOver || finish->settled());
  out.equilibrium = eq;
  out.equilibrium["reached"] = out.reached;
  out.equilibrium["simulated_time"] = c.simTime;
  out.equilibrium["time_limit"] = def.timeLimit;

  nlohmann::json phases = nlohmann::json::object();
  for (int k = 0; k < static_cast<int>(core::Phase::Count); ++k)
    phases[std::string(core::toString(static_cast<core::Phase>(k)))] = c.phaseSeconds[k];
  const double solveSeconds = c.phaseSeconds[static_cast<int>(core::Phase::Solve)];
  nlohmann::json history = nlohmann::json::array();
  for (const CheckPoint& p : out.history)
    history.push_back({{"steps", p.steps},
                       {"time", p.time},
                       {"wall_s", p.wallSeconds},
                       {"max_force_ratio", p.maxForceRatio},
                       {"max_moment_ratio", p.maxMomentRatio},
                       {"max_kinetic_ratio", p.maxKineticRatio},
                       {"interpenetration_percent", p.interpenetrationPercent},
                       {"iterations", p.iterations}});
  nlohmann::json stages = {{"dynamic",
                            {{"steps", c.dynamicSteps},
                             {"simulated_time", c.simTime},
                             {"iterations", c.dynamicIterations},
                             {"wall_s", c.dynamicWallSeconds}}}};
  const double wall = elapsed();
  if (handOver)
    stages["quasi_static"] = {{"handed_over_at", c.handOverAt},
                              {"mean_kinetic_ratio_at_hand_over", c.handOverKineticRatio},
                              {"steps", finish->steps()},
                              {"clipped_steps", finish->clippedSteps()},
                              {"iterations", c.iterations - c.dynamicIterations},
                              {"wall_s", wall - c.dynamicWallSeconds},
                              {"last_step", finish->lastStepLength()},
                              {"last_displacement", finish->lastMove().maxDisplacement}};
  if (handOver) stages["quasi_static"].update(backend->finisherReport());
  out.timing = {{"wall_s", wall},
                {"compaction_s", wall},
                {"protocol", core::toString(out.protocol)},
                {"stages", stages},
                {"steps", c.steps},
                {"dt", out.dt},
                {"dt_largest", out.dtLargest},
                {"iterations", c.iterations},
                {"iterations_per_step", c.steps > 0 ? static_cast<double>(c.iterations) / c.steps : 0.0},
                {"contact_updates_per_s", solveSeconds > 0.0 ? c.rowUpdates / solveSeconds : 0.0},
                {"phases", phases},
                {"history", history}};
  // Only where the run was given a checkpoint file, so that other runs' result.json is unchanged.
  if (!checkpointing.file.empty()) {
    // earlier_s: the wall time of the invocations this one resumed, up to their last checkpoint.
    out.timing["checkpoint"] = {{"resumes", c.resumes},
                                {"exact", backend->exactRestore()},
                                {"earlier_s", resumed ? resumed->counters.elapsedSeconds : 0.0}};
    if (!ignoredWhy.empty()) out.timing["checkpoint"]["ignored"] = ignoredWhy;
  }
  out.backendSettings = backend->settings();
  return out;
}

namespace {
// The metadata lines of a run's profiles (analysis::writeProfiles).
nlohmann::json profileMetadata(const nlohmann::json& seed, const std::string& backend) {
  return {{"seed", seed}, {"backend", backend}, {"version", core::version()}, {"revision", core::sourceRevision()}};
}

// The keys of result.json that makeResult writes beside the analysis blocks: the compaction's.
constexpr std::array<std::string_view, 9> kCompactionKeys = {
    "backend", "seed",   "n_grains",         "equilibrium",      "timing",
    "deposit", "config", "confpack_version", "confpack_revision"};
}  // namespace

nlohmann::json makeResult(const core::RunConfig& cfg, const core::Deposit& deposit, const CompactionOutcome& out,
                          const analysis::Analysis& measured) {
  nlohmann::json r = analysis::toJson(measured);
  // Every key set here is one of kCompactionKeys, which reanalyseRun keeps.
  r["backend"] = cfg.backend;
  r["seed"] = cfg.seed;
  r["n_grains"] = out.packing.grains.size();
  r["equilibrium"] = out.equilibrium;
  r["timing"] = out.timing;
  r["timing"]["deposit_s"] = deposit.seconds;
  r["timing"]["wall_s"] = out.timing["compaction_s"].get<double>() + deposit.seconds;
  r["deposit"] = {{"pile_height", deposit.pileHeight},
                  {"placeholder_diameter", deposit.placeholderDiameter},
                  {"solid_fraction", deposit.solidFraction}};
  if (!deposit.source.empty()) r["deposit"]["from"] = deposit.source;
  r["config"] = cfg;
  r["config"]["backend_settings"] = out.backendSettings;
  r["config"]["compaction"]["dt"] = out.dt;
  r["confpack_version"] = core::version();
  r["confpack_revision"] = core::sourceRevision();
  return r;
}

Reanalysed reanalyseRun(const std::filesystem::path& runDir) {
  const std::filesystem::path resultFile = runDir / "result.json";
  Reanalysed r{core::readJsonFile(resultFile, "result file"), nlohmann::json()};
  if (!r.before.is_object()) throw std::invalid_argument(fmt::format("{}: not a JSON object", resultFile.string()));
  const analysis::Analysis measured = analysis::analyze(core::readPacking(runDir / "packing.json"), analysisOptions());
  r.after = analysis::toJson(measured);
  for (std::string_view key : kCompactionKeys)
    if (r.before.contains(key)) r.after[std::string(key)] = r.before[std::string(key)];
  analysis::writeProfiles(runDir, measured,
                          profileMetadata(r.before.value("seed", nlohmann::json()), r.before.value("backend", "")));
  core::writeFileAtomically(resultFile, r.after.dump(2));
  return r;
}

FinishedRun runProtocol(const core::RunConfig& cfg, const std::filesystem::path& vtkDir, const RunProgressFn& progress,
                        const core::Deposit* shared, const Checkpointing& checkpointing) {
  const core::Deposit dep = shared ? *shared : core::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  CompactionOutcome out = compact(cfg, dep, vtkDir, progress, checkpointing);
  analysis::Analysis measured = analysis::analyze(out.packing, analysisOptions());
  nlohmann::json result = makeResult(cfg, dep, out, measured);
  return {std::move(out.packing), std::move(measured), std::move(result)};
}

nlohmann::json runAndWrite(const core::RunConfig& cfg, const std::filesystem::path& outDir,
                           const RunProgressFn& progress, const core::Deposit* shared,
                           const Checkpointing& checkpointing) {
  const FinishedRun run = runProtocol(cfg, outDir / "vtk", progress, shared, checkpointing);
  core::writePacking(run.packing, outDir / "packing.json");
  analysis::writeProfiles(outDir, run.measured, profileMetadata(cfg.seed, cfg.backend));
  core::writeFileAtomically(outDir / "result.json", run.result.dump(2));
  if (!checkpointing.file.empty()) {
    std::error_code ignored;  // a checkpoint left behind is ignored once the run is done
    std::filesystem::remove(checkpointing.file, ignored);
  }
  return run.result;
}

}  // namespace confpack::study
