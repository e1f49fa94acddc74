#include "study/run_pipeline.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <stdexcept>

#include "analysis/equilibrium.hpp"
#include "analysis/interpenetration.hpp"
#include "backends/backend_factory.hpp"
#include "core/interrupt.hpp"
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
  radius_.reserve(grains.size());
  for (const core::Grain& g : grains) radius_.push_back(g.boundingRadius());
  motion_ = 0.01 * core::smallestSize(grains);
}

double AdaptiveTimeStep::next(double previous, const std::vector<core::BodyState>& states) const {
  if (radius_.empty()) return floor_;
  double v = 0.0;
  for (std::size_t i = 0; i < radius_.size(); ++i)
    v = std::max(v, states[i].velocity.norm() + states[i].angularVelocity.norm() * radius_[i]);
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
                          const RunProgressFn& progress) {
  const auto start = Clock::now();
  core::SystemDef system;
  system.box = cfg.box;
  system.walls = cfg.walls;
  system.grains = deposit.grains;
  system.threads = cfg.threads;
  auto backend = backends::makeBackend(cfg.backend, system,
                                       cfg.backendOptions.is_null() ? nlohmann::json::object() : cfg.backendOptions);
  const core::CompactionDef& def = cfg.compaction;

  CompactionOutcome out;
  out.dt = def.dt > 0.0 ? def.dt : defaultTimeStep(cfg, deposit);
  out.dtLargest = out.dt;
  const bool adaptive = def.adaptiveDt;
  // Bullet has no finisher: its runs stay dynamic, and result.json says which protocol ran.
  const bool finisher = def.protocol == core::Protocol::QuasiStatic && backend->hasQuasiStaticStep();
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
  double simTime = 0.0, lastCheckTime = 0.0;
  double dt = out.dt;

  std::optional<core::VtkSeries> frames;
  if (!vtkDir.empty()) {
    frames.emplace(vtkDir, "frame");
    core::Packing initial{cfg.box, cfg.walls, deposit.grains, std::nullopt};
    frames->addFrame(0.0, initial);
  }

  core::StepProfile totals;
  long steps = 0;
  long totalIterations = 0;
  double rowUpdates = 0.0;  // contact rows x sweeps, for contact updates per second
  analysis::EquilibriumReport eq;
  bool haveEq = false;
  double stepSeconds = 0.0;  // wall time inside the backend's steps, without checks and frames
  double stepCpuSeconds = 0.0;  // the same in CPU time
  // One step of either stage: time it and add its profile to the totals.
  auto timed = [&](auto&& stepFn) {
    const Clock::time_point stepStart = Clock::now();
    const double cpuStart = processCpuSeconds();
    stepFn();
    stepSeconds += secondsSince(stepStart);
    stepCpuSeconds += processCpuSeconds() - cpuStart;
    ++steps;
    const core::StepProfile& prof = backend->profile();
    for (std::size_t k = 0; k < totals.seconds.size(); ++k) totals.seconds[k] += prof.seconds[k];
    totalIterations += prof.iterations;
    rowUpdates += static_cast<double>(prof.contactPoints) * prof.iterations;
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
    out.history.push_back({steps, simTime, secondsSince(start), eq.maxForceRatio, eq.maxMomentRatio,
                           eq.maxKineticRatio, overlap, totalIterations, rowUpdates, totals[core::Phase::Solve],
                           stepSeconds, stepCpuSeconds});
    if (progress)
      progress(fraction, fmt::format("{} {} step {} iterations/step {:.1f} force {:.1e} moment {:.1e} kinetic {:.1e}",
                                     backend->name(), stage, steps, static_cast<double>(totalIterations) / steps,
                                     eq.maxForceRatio, eq.maxMomentRatio, eq.maxKineticRatio));
  };

  // Stage 1: time steps, until equilibrium, the time limit, or (quasi-static protocol) the end of
  // the fall.
  bool handOver = false;
  while (adaptive ? simTime < timeLimit : steps < maxSteps) {
    if (core::stopSignal() != 0)
      throw core::Interrupted(core::stopSignal(), fmt::format("at t = {:.3g} (step {})", simTime, steps));
    if (adaptive && steps > 0) {
      dt = adaptiveStep.next(dt, backend->states());
      out.dtLargest = std::max(out.dtLargest, dt);
    }
    timed([&] { backend->step(dt); });
    simTime = adaptive ? simTime + dt : static_cast<double>(steps) * out.dt;
    const bool lastStep = adaptive ? simTime >= timeLimit : steps == maxSteps;

    const bool frameDue = frames && def.frameInterval > 0 && steps % def.frameInterval == 0;
    const bool checkDue = steps % def.checkInterval == 0 || lastStep ||
                          (adaptive && simTime - lastCheckTime >= kAdaptiveCheckSpacing);
    if (!frameDue && !checkDue) continue;
    const core::Packing now = snapshot(cfg, deposit.grains, *backend);
    if (frameDue) frames->addFrame(simTime, now, velocities(backend->states()));
    if (checkDue) {
      lastCheckTime = simTime;
      check(now, std::min(1.0, simTime / timeLimit),
            fmt::format("t={:.1f}{}", simTime, adaptive ? fmt::format(" dt {:.1e}", dt) : ""));
      if (eq.reached) break;
      if (finisher && eq.meanKineticRatio < def.switchKineticRatio) {
        handOver = true;
        break;
      }
    }
  }
  // The quasi-static protocol's dynamic stage ends at the time limit too: the finisher takes over
  // from there, bounded by its own step count. `handOverAt` says which ended the fall.
  const char* handOverAt = handOver ? "switch_kinetic_ratio" : nullptr;
  if (finisher && !handOver && !eq.reached) {
    handOver = true;
    handOverAt = fallBounded ? "fall_time_limit" : "time_limit";
  }
  // How far the fall had got when the finisher took over: the finisher is meant for the creep after
  // the fall (docs/model.md), and this shows a pile it was handed while still falling.
  const double handOverKineticRatio = haveEq ? eq.meanKineticRatio : 0.0;
  const long dynamicSteps = steps;
  const long dynamicIterations = totalIterations;
  const double dynamicWall = secondsSince(start);

  // Stage 2 (quasi-static protocol): the finisher's steps from rest
  // (core/quasi_static_finisher.hpp). The equilibrium test is checked after each step that moved
  // nothing more than the settle tolerance (and every 20 steps, for the progress line); the
  // finisher stops once it holds there.
  core::QuasiStaticFinisher finish(def, core::smallestSize(deposit.grains), dt);
  if (handOver) {
    for (long k = 1; k <= def.finisherMaxSteps; ++k) {
      if (core::stopSignal() != 0)
        throw core::Interrupted(core::stopSignal(), fmt::format("in finisher step {} of the quasi-static protocol", k));
      timed([&] { finish.step(*backend); });
      const bool last = k == def.finisherMaxSteps;
      const bool frameDue = frames && def.frameInterval > 0 && steps % def.frameInterval == 0;
      if (!frameDue && !last && !finish.settled() && k % 20 != 0) continue;
      const core::Packing now = snapshot(cfg, deposit.grains, *backend);
      if (frameDue) frames->addFrame(simTime, now, velocities(backend->states()));
      check(now, static_cast<double>(k) / def.finisherMaxSteps,
            fmt::format("finisher {} h {:.1e} moved {:.1e}", k, finish.lastStepLength(),
                        finish.lastMove().maxDisplacement));
      if (eq.reached && finish.settled()) break;
    }
  }

  out.packing = snapshot(cfg, deposit.grains, *backend);
  out.states = backend->states();
  if (!haveEq)
    eq = analysis::equilibrium(out.packing, out.states, system.gravity, system.density, def.forceRatio,
                               def.momentRatio, def.kineticRatio);
  if (frames) {
    frames->addFrame(simTime, out.packing, velocities(out.states));
    frames->finish();
  }
  // With the finisher, equilibrium also needs its last step to have moved (almost) nothing: its
  // steps are so long that the force and kinetic ratios of a step say little about motion.
  out.reached = eq.reached && (!handOver || finish.settled());
  out.equilibrium = eq;
  out.equilibrium["reached"] = out.reached;
  out.equilibrium["simulated_time"] = simTime;
  out.equilibrium["time_limit"] = def.timeLimit;

  nlohmann::json phases = nlohmann::json::object();
  for (int k = 0; k < static_cast<int>(core::Phase::Count); ++k)
    phases[std::string(core::toString(static_cast<core::Phase>(k)))] = totals.seconds[k];
  const double solveSeconds = totals[core::Phase::Solve];
  nlohmann::json history = nlohmann::json::array();
  for (const CheckPoint& c : out.history)
    history.push_back({{"steps", c.steps}, {"time", c.time}, {"wall_s", c.wallSeconds},
                       {"max_force_ratio", c.maxForceRatio}, {"max_moment_ratio", c.maxMomentRatio},
                       {"max_kinetic_ratio", c.maxKineticRatio}, {"interpenetration_percent", c.interpenetrationPercent},
                       {"iterations", c.iterations}});
  nlohmann::json stages = {{"dynamic",
                            {{"steps", dynamicSteps},
                             {"simulated_time", simTime},
                             {"iterations", dynamicIterations},
                             {"wall_s", dynamicWall}}}};
  if (handOver)
    stages["quasi_static"] = {{"handed_over_at", handOverAt},
                              {"mean_kinetic_ratio_at_hand_over", handOverKineticRatio},
                              {"steps", finish.steps()},
                              {"clipped_steps", finish.clippedSteps()},
                              {"iterations", totalIterations - dynamicIterations},
                              {"wall_s", secondsSince(start) - dynamicWall},
                              {"last_step", finish.lastStepLength()},
                              {"last_displacement", finish.lastMove().maxDisplacement}};
  out.timing = {{"wall_s", secondsSince(start)},
                {"compaction_s", secondsSince(start)},
                {"protocol", core::toString(out.protocol)},
                {"stages", stages},
                {"steps", steps},
                {"dt", out.dt},
                {"dt_largest", out.dtLargest},
                {"iterations", totalIterations},
                {"iterations_per_step", steps > 0 ? static_cast<double>(totalIterations) / steps : 0.0},
                {"contact_updates_per_s", solveSeconds > 0.0 ? rowUpdates / solveSeconds : 0.0},
                {"phases", phases},
                {"history", history}};
  out.backendSettings = backend->settings();
  return out;
}

nlohmann::json makeResult(const core::RunConfig& cfg, const core::Deposit& deposit, const CompactionOutcome& out,
                          const analysis::Analysis& measured) {
  nlohmann::json r = analysis::toJson(measured);
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
  r["confpack_version"] = CONFPACK_VERSION;
  return r;
}

FinishedRun runProtocol(const core::RunConfig& cfg, const std::filesystem::path& vtkDir, const RunProgressFn& progress,
                        const core::Deposit* shared) {
  const core::Deposit dep = shared ? *shared : core::deposit(cfg.box, cfg.population, cfg.deposition, cfg.seed);
  CompactionOutcome out = compact(cfg, dep, vtkDir, progress);
  analysis::Analysis measured = analysis::analyze(out.packing, analysisOptions());
  nlohmann::json result = makeResult(cfg, dep, out, measured);
  return {std::move(out.packing), std::move(measured), std::move(result)};
}

nlohmann::json runAndWrite(const core::RunConfig& cfg, const std::filesystem::path& outDir,
                           const RunProgressFn& progress, const core::Deposit* shared) {
  const FinishedRun run = runProtocol(cfg, outDir / "vtk", progress, shared);
  core::writePacking(run.packing, outDir / "packing.json");
  analysis::writeProfiles(outDir, run.measured,
                          {{"seed", cfg.seed}, {"backend", cfg.backend}, {"version", CONFPACK_VERSION}});
  core::writeFileAtomically(outDir / "result.json", run.result.dump(2));
  return run.result;
}

}  // namespace confpack::study
