#include "compaction/compaction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "analysis/coordination.hpp"
#include "analysis/equilibrium.hpp"
#include "analysis/interpenetration.hpp"
#include "analysis/solid_fraction.hpp"
#include "backends/backend_factory.hpp"
#include "compaction/quasi_static_finisher.hpp"
#include "compaction/time_step.hpp"
#include "core/interrupt.hpp"
#include "core/vtk_writer.hpp"

namespace confpack::compaction {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

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

// A history number for result.json: null where it was not measured (JSON has no NaN).
nlohmann::json number(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

std::vector<core::Vec3> velocities(const std::vector<core::BodyState>& states) {
  std::vector<core::Vec3> v;
  v.reserve(states.size());
  for (const auto& s : states) v.push_back(s.velocity);
  return v;
}

/// The bulk's solid fraction and coordination at a check, as the final analysis measures them
/// (force-carrying contacts of the backend's last step); NaN without a bulk region or, for Z,
/// without a grain in it.
struct Relaxation {
  double solidFraction = std::numeric_limits<double>::quiet_NaN();
  double coordination = std::numeric_limits<double>::quiet_NaN();
};

Relaxation relaxation(const core::Packing& now, const analysis::BulkRegion& region) {
  Relaxation r;
  if (region.empty() || !now.contacts) return r;
  r.solidFraction = analysis::solidFraction(now, region).phi;
  const analysis::Coordination c = analysis::bulkCoordination(now, region);
  if (c.bulkGrains > 0) r.coordination = c.z;  // as result.json: no Z without a grain to count it on
  return r;
}

/// What the configuration and the backend fix for the whole compaction: its step and its limits.
struct Schedule {
  double dt = 0.0;           ///< the fixed step, or the adaptive step's floor [t0]
  bool adaptive = false;     ///< compaction.adaptive_dt
  bool finisher = false;     ///< quasi-static protocol on a backend that has a finisher
  bool fallBounded = false;  ///< the fall ends at fall_time_limit, not time_limit
  double timeLimit = 0.0;    ///< of the dynamic stage [t0]
  long maxSteps = 0;         ///< of a fixed-step dynamic stage
};

Schedule makeSchedule(const core::RunConfig& cfg, const Deposit& deposit, const core::ContactBackend& backend) {
  const core::CompactionDef& def = cfg.compaction;
  Schedule s;
  s.dt = def.dt > 0.0 ? def.dt : defaultTimeStep(cfg, deposit);
  s.adaptive = def.adaptiveDt;
  // Bullet has no finisher: its runs stay dynamic, and result.json says which protocol ran.
  s.finisher = def.protocol == core::Protocol::QuasiStatic && backend.hasQuasiStaticStep();
  // With the finisher, the dynamic steps are the fall, bounded by fall_time_limit when given.
  s.fallBounded = s.finisher && def.fallTimeLimit > 0.0;
  s.timeLimit = s.fallBounded ? def.fallTimeLimit : def.timeLimit;
  // A fixed step runs ceil(limit / dt) steps, its time counted as steps x dt (no round-off drift);
  // an adaptive one sums its steps until the sum reaches the limit.
  // A step count a long holds exactly (time_limit is bounded by validation; a tiny --dt is not).
  const double stepsToLimit = std::ceil(s.timeLimit / s.dt);
  if (!(stepsToLimit < 0x1p53))
    throw std::invalid_argument(fmt::format(
        "compaction: time_limit {:g} t0 at dt {:g} t0 is more steps than can be counted", s.timeLimit, s.dt));
  s.maxSteps = static_cast<long>(stepsToLimit);
  return s;
}

/// One compaction, as named stages: start (or resume), fall, hand over, finish, outcome.
class Driver {
 public:
  Driver(const core::RunConfig& cfg, const Deposit& deposit, const std::filesystem::path& vtkDir,
         const CompactionProgressFn& progress, const Checkpointing& checkpointing);

  CompactionOutcome run() {
    fall();
    handOver();
    if (handOver_) finishQuasiStatically();
    return outcome();
  }

 private:
  void start();
  void fall();
  void handOver();
  void finishQuasiStatically();
  CompactionOutcome outcome();
  nlohmann::json timingJson(const CompactionOutcome& out) const;

  void makeFinisher(double firstStep) {
    finish_.emplace(cfg_.compaction, core::smallestSize(deposit_.grains), firstStep);
  }
  template <class StepFn>
  void timedStep(StepFn&& stepFn);
  void check(const core::Packing& now, double fraction, const std::string& stage);
  double elapsed() const { return c_.elapsedSeconds + secondsSince(start_); }
  void save();
  void stopIfAsked(const std::string& where);
  void saveIfDue() {
    if (!checkpointing_.file.empty() && secondsSince(lastSave_) >= checkpointing_.everySeconds) save();
  }

  const core::RunConfig& cfg_;
  const Deposit& deposit_;
  const CompactionProgressFn& progress_;
  const Checkpointing& checkpointing_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point lastSave_;
  nlohmann::json identity_;                  ///< what a checkpoint must match (empty: none kept)
  std::optional<LoadedCheckpoint> resumed_;  ///< the checkpoint this run resumed from
  std::string ignoredWhy_;                   ///< why a checkpoint found was not resumed
  core::SystemDef system_;
  std::unique_ptr<core::ContactBackend> backend_;
  /// The finisher's first step is the last dynamic one; it is made at the hand-over, or at the
  /// start of a run resumed in its finisher.
  std::optional<QuasiStaticFinisher> finish_;
  Schedule schedule_;
  std::optional<AdaptiveTimeStep> adaptiveStep_;
  CompactionCounters c_;  ///< where the compaction stands; a resumed run takes it over
  std::optional<core::VtkSeries> frames_;
  analysis::EquilibriumReport eq_;
  bool haveEq_ = false;
  bool handOver_ = false;
};

Driver::Driver(const core::RunConfig& cfg, const Deposit& deposit, const std::filesystem::path& vtkDir,
               const CompactionProgressFn& progress, const Checkpointing& checkpointing)
    : cfg_(cfg), deposit_(deposit), progress_(progress), checkpointing_(checkpointing) {
  start();
  schedule_ = makeSchedule(cfg_, deposit_, *backend_);
  if (schedule_.finisher) backend_->startQuasiStaticFall();
  adaptiveStep_.emplace(deposit_.grains, system_.gravity.norm(), schedule_.dt);
  c_.dt = schedule_.dt;
  c_.dtLargest = schedule_.dt;
  if (resumed_) {
    c_ = resumed_->counters;
    ++c_.resumes;
  }
  lastSave_ = Clock::now();
  if (!vtkDir.empty()) {
    frames_.emplace(vtkDir, "frame");
    core::Packing initial{cfg_.box, cfg_.walls, deposit_.grains, std::nullopt};
    frames_->addFrame(0.0, initial);
  }
}

// Builds the backend: at the poses and with the state of a checkpoint of this run if there is
// one that fits, from the deposit otherwise.
void Driver::start() {
  if (!checkpointing_.file.empty()) {
    identity_ = checkpointIdentity(cfg_, deposit_);
    resumed_ = readCheckpoint(checkpointing_.file, identity_, ignoredWhy_);
  }
  system_.box = cfg_.box;
  system_.walls = cfg_.walls;
  system_.grains = deposit_.grains;
  system_.threads = cfg_.threads;
  const auto makeBackend = [&] {
    return backends::makeBackend(cfg_.backend, system_,
                                 cfg_.backendOptions.is_null() ? nlohmann::json::object() : cfg_.backendOptions);
  };
  if (resumed_) {
    try {
      const std::vector<core::BodyState> saved =
          core::bodyStatesFromJson(resumed_->backend.value("grains", nlohmann::json()), deposit_.grains.size());
      for (std::size_t i = 0; i < saved.size(); ++i) {
        system_.grains[i].position = saved[i].position;
        system_.grains[i].orientation = saved[i].orientation;
      }
      if (resumed_->counters.finisherStage) {
        makeFinisher(resumed_->counters.dt);
        finish_->restoreState(resumed_->finisher);
      }
      backend_ = makeBackend();
      backend_->restoreState(resumed_->backend);
    } catch (const std::exception& e) {
      ignoredWhy_ = fmt::format("its state does not fit ({})", e.what());
      resumed_.reset();
      backend_.reset();
      finish_.reset();
      system_.grains = deposit_.grains;
    }
  }
  if (!backend_) backend_ = makeBackend();
}

void Driver::save() {
  CompactionCounters now = c_;
  now.elapsedSeconds = elapsed();
  writeCheckpoint(checkpointing_.file, identity_, now, backend_->saveState(),
                  finish_ ? finish_->saveState() : nlohmann::json());
  lastSave_ = Clock::now();
}

// At the top of a step: a stop signal saves the state before the run gives up, and so does the
// first check after every checkpointing.everySeconds.
void Driver::stopIfAsked(const std::string& where) {
  if (core::stopSignal() == 0) return;
  if (checkpointing_.file.empty()) throw core::Interrupted(core::stopSignal(), where);
  save();
  throw core::Interrupted(core::stopSignal(), fmt::format("{}; its state is saved in {}; the same command resumes it",
                                                          where, checkpointing_.file.string()));
}

// One step of either stage: time it and add its profile to the totals.
template <class StepFn>
void Driver::timedStep(StepFn&& stepFn) {
  const Clock::time_point stepStart = Clock::now();
  const double cpuStart = processCpuSeconds();
  stepFn();
  c_.stepSeconds += secondsSince(stepStart);
  c_.stepCpuSeconds += processCpuSeconds() - cpuStart;
  ++c_.steps;
  const core::StepProfile& prof = backend_->profile();
  for (std::size_t k = 0; k < c_.phaseSeconds.size(); ++k) c_.phaseSeconds[k] += prof.seconds[k];
  c_.iterations += prof.iterations;
  c_.rowUpdates += static_cast<double>(prof.contactPoints) * prof.iterations;
}

// The equilibrium test (docs/model.md, "Equilibrium") of the state now, recorded in the history
// and reported as progress.
void Driver::check(const core::Packing& now, double fraction, const std::string& stage) {
  const core::CompactionDef& def = cfg_.compaction;
  eq_ = analysis::equilibrium(now, backend_->states(), system_.gravity, system_.density, def.forceRatio,
                              def.momentRatio, def.kineticRatio);
  haveEq_ = true;
  const analysis::BulkRegion region = analysis::bulkRegion(now);
  analysis::InterpenetrationDef exactOnly;
  exactOnly.lattice = false;  // the lattice bounds are for the final state only (costly)
  const double overlap = analysis::interpenetration(now, region, exactOnly).exactPercent;
  const Relaxation relaxed = relaxation(now, region);
  c_.history.push_back({c_.steps, c_.simTime, elapsed(), eq_.maxForceRatio, eq_.maxMomentRatio, eq_.maxKineticRatio,
                        overlap, c_.iterations, c_.rowUpdates, c_.phaseSeconds[static_cast<int>(core::Phase::Solve)],
                        c_.stepSeconds, c_.stepCpuSeconds, relaxed.solidFraction, relaxed.coordination});
  if (progress_)
    progress_(fraction, fmt::format("{} {} step {} iterations/step {:.1f} force {:.1e} moment {:.1e} kinetic {:.1e}",
                                    backend_->name(), stage, c_.steps, static_cast<double>(c_.iterations) / c_.steps,
                                    eq_.maxForceRatio, eq_.maxMomentRatio, eq_.maxKineticRatio));
}

// Stage 1: time steps, until equilibrium, the time limit, or (quasi-static protocol) the end of
// the fall.
void Driver::fall() {
  const core::CompactionDef& def = cfg_.compaction;
  const Schedule& s = schedule_;
  handOver_ = c_.finisherStage;
  while (!c_.finisherStage && (s.adaptive ? c_.simTime < s.timeLimit : c_.steps < s.maxSteps)) {
    stopIfAsked(fmt::format("at t = {:.3g} (step {})", c_.simTime, c_.steps));
    if (s.adaptive && c_.steps > 0) {
      c_.dt = adaptiveStep_->next(c_.dt, backend_->states());
      c_.dtLargest = std::max(c_.dtLargest, c_.dt);
    }
    timedStep([&] { backend_->step(c_.dt); });
    c_.simTime = s.adaptive ? c_.simTime + c_.dt : static_cast<double>(c_.steps) * s.dt;
    const bool lastStep = s.adaptive ? c_.simTime >= s.timeLimit : c_.steps == s.maxSteps;

    const bool frameDue = frames_ && def.frameInterval > 0 && c_.steps % def.frameInterval == 0;
    const bool checkDue = c_.steps % def.checkInterval == 0 || lastStep ||
                          (s.adaptive && c_.simTime - c_.lastCheckTime >= kAdaptiveCheckSpacing);
    if (!frameDue && !checkDue) continue;
    const core::Packing now = snapshot(cfg_, deposit_.grains, *backend_);
    if (frameDue) frames_->addFrame(c_.simTime, now, velocities(backend_->states()));
    if (checkDue) {
      c_.lastCheckTime = c_.simTime;
      check(now, std::min(1.0, c_.simTime / s.timeLimit),
            fmt::format("t={:.1f}{}", c_.simTime, s.adaptive ? fmt::format(" dt {:.1e}", c_.dt) : ""));
      if (eq_.reached) break;
      if (s.finisher && eq_.meanSettlingKineticRatio < def.switchKineticRatio) {
        handOver_ = true;
        c_.handOverAt = "switch_kinetic_ratio";
        break;
      }
      if (!lastStep) saveIfDue();
    }
  }
}

// The quasi-static protocol's dynamic stage ends at the time limit too: the finisher takes over
// from there, bounded by its own step count. handOverAt says which ended the fall; how far the
// fall had got shows a pile the finisher (meant for the creep after the fall, docs/model.md) was
// handed while still falling.
void Driver::handOver() {
  if (c_.finisherStage) return;
  if (schedule_.finisher && !handOver_ && !eq_.reached) {
    handOver_ = true;
    c_.handOverAt = schedule_.fallBounded ? "fall_time_limit" : "time_limit";
  }
  c_.handOverKineticRatio = haveEq_ ? eq_.meanSettlingKineticRatio : 0.0;
  c_.dynamicSteps = c_.steps;
  c_.dynamicIterations = c_.iterations;
  c_.dynamicWallSeconds = elapsed();
  c_.finisherStage = handOver_;
  if (handOver_) makeFinisher(c_.dt);
}

// Stage 2 (quasi-static protocol): the finisher's steps from rest
// (compaction/quasi_static_finisher.hpp). The equilibrium test is checked after each step that
// moved nothing more than the settle tolerance (and every 20 steps, for the progress line); the
// finisher stops once it holds there.
void Driver::finishQuasiStatically() {
  const core::CompactionDef& def = cfg_.compaction;
  for (long k = finish_->steps() + 1; k <= def.finisherMaxSteps; ++k) {
    stopIfAsked(fmt::format("in finisher step {} of the quasi-static protocol", k));
    timedStep([&] { finish_->step(*backend_); });
    const bool last = k == def.finisherMaxSteps;
    const bool frameDue = frames_ && def.frameInterval > 0 && c_.steps % def.frameInterval == 0;
    if (!frameDue && !last && !finish_->settled() && k % 20 != 0) continue;
    const core::Packing now = snapshot(cfg_, deposit_.grains, *backend_);
    if (frameDue) frames_->addFrame(c_.simTime, now, velocities(backend_->states()));
    check(now, static_cast<double>(k) / def.finisherMaxSteps,
          fmt::format("finisher {} h {:.1e} moved {:.1e}", k, finish_->lastStepLength(),
                      finish_->lastMove().maxDisplacement));
    if (eq_.reached && finish_->settled()) break;
    if (!last) saveIfDue();
  }
}

CompactionOutcome Driver::outcome() {
  const core::CompactionDef& def = cfg_.compaction;
  CompactionOutcome out;
  out.dt = schedule_.dt;
  out.protocol = schedule_.finisher ? core::Protocol::QuasiStatic : core::Protocol::Dynamic;
  out.packing = snapshot(cfg_, deposit_.grains, *backend_);
  out.states = backend_->states();
  out.history = c_.history;
  out.dtLargest = c_.dtLargest;
  if (!haveEq_)
    eq_ = analysis::equilibrium(out.packing, out.states, system_.gravity, system_.density, def.forceRatio,
                                def.momentRatio, def.kineticRatio);
  if (frames_) {
    frames_->addFrame(c_.simTime, out.packing, velocities(out.states));
    frames_->finish();
  }
  // With the finisher, equilibrium also needs its last step to have moved (almost) nothing: its
  // steps are so long that the force and kinetic ratios of a step say little about motion.
  out.reached = eq_.reached && (!handOver_ || finish_->settled());
  out.equilibrium = eq_;
  out.equilibrium["reached"] = out.reached;
  out.equilibrium["simulated_time"] = c_.simTime;
  out.equilibrium["time_limit"] = def.timeLimit;
  out.timing = timingJson(out);
  out.backendSettings = backend_->settings();
  return out;
}

// result.json's timing block: totals, the two stages, the phases and the history of checks.
nlohmann::json Driver::timingJson(const CompactionOutcome& out) const {
  nlohmann::json phases = nlohmann::json::object();
  for (int k = 0; k < static_cast<int>(core::Phase::Count); ++k)
    phases[std::string(core::toString(static_cast<core::Phase>(k)))] = c_.phaseSeconds[k];
  const double solveSeconds = c_.phaseSeconds[static_cast<int>(core::Phase::Solve)];
  nlohmann::json history = nlohmann::json::array();
  for (const CheckPoint& p : out.history)
    history.push_back({{"steps", p.steps},
                       {"time", p.time},
                       {"wall_s", p.wallSeconds},
                       {"max_force_ratio", p.maxForceRatio},
                       {"max_moment_ratio", p.maxMomentRatio},
                       {"max_kinetic_ratio", p.maxKineticRatio},
                       {"interpenetration_percent", p.interpenetrationPercent},
                       {"iterations", p.iterations},
                       {"solid_fraction", number(p.solidFraction)},
                       {"Z", number(p.coordination)}});
  nlohmann::json stages = {{"dynamic",
                            {{"steps", c_.dynamicSteps},
                             {"simulated_time", c_.simTime},
                             {"iterations", c_.dynamicIterations},
                             {"wall_s", c_.dynamicWallSeconds}}}};
  const double wall = elapsed();
  if (handOver_) {
    stages["quasi_static"] = {{"handed_over_at", c_.handOverAt},
                              {"mean_kinetic_ratio_at_hand_over", c_.handOverKineticRatio},
                              {"steps", finish_->steps()},
                              {"clipped_steps", finish_->clippedSteps()},
                              {"iterations", c_.iterations - c_.dynamicIterations},
                              {"wall_s", wall - c_.dynamicWallSeconds},
                              {"last_step", finish_->lastStepLength()},
                              {"last_displacement", finish_->lastMove().maxDisplacement}};
    stages["quasi_static"].update(backend_->finisherReport());
  }
  nlohmann::json timing = {{"wall_s", wall},
                           {"compaction_s", wall},
                           {"protocol", core::toString(out.protocol)},
                           {"stages", stages},
                           {"steps", c_.steps},
                           {"dt", out.dt},
                           {"dt_largest", out.dtLargest},
                           {"iterations", c_.iterations},
                           {"iterations_per_step", c_.steps > 0 ? static_cast<double>(c_.iterations) / c_.steps : 0.0},
                           {"contact_updates_per_s", solveSeconds > 0.0 ? c_.rowUpdates / solveSeconds : 0.0},
                           {"phases", phases},
                           {"history", history}};
  // Only where the run was given a checkpoint file, so that other runs' result.json is unchanged.
  if (!checkpointing_.file.empty()) {
    // earlier_s: the wall time of the invocations this one resumed, up to their last checkpoint.
    timing["checkpoint"] = {{"resumes", c_.resumes},
                            {"exact", backend_->exactRestore()},
                            {"earlier_s", resumed_ ? resumed_->counters.elapsedSeconds : 0.0}};
    if (!ignoredWhy_.empty()) timing["checkpoint"]["ignored"] = ignoredWhy_;
  }
  return timing;
}

}  // namespace

Deposit depositFromPacking(const core::Packing& packing, const std::filesystem::path& source) {
  if (packing.grains.empty())
    throw std::invalid_argument(fmt::format("{}: the packing has no grains", source.string()));
  Deposit d;
  d.grains = packing.grains;
  for (const core::Grain& g : d.grains) d.pileHeight = std::max(d.pileHeight, g.position.z() + g.boundingRadius());
  d.solidFraction = core::totalVolume(d.grains) / (packing.box.lengthX * packing.box.width * d.pileHeight);
  d.source = source.string();
  d.contacts = packing.contacts;
  return d;
}

CompactionOutcome compact(const core::RunConfig& cfg, const Deposit& deposit, const std::filesystem::path& vtkDir,
                          const CompactionProgressFn& progress, const Checkpointing& checkpointing) {
  return Driver(cfg, deposit, vtkDir, progress, checkpointing).run();
}

}  // namespace confpack::compaction
