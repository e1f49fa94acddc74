// The sweep engine (study/sweep.hpp): runSweep and its workers, which take this task's unfinished
// runs one at a time, claim each (study/run_claim.hpp), compact it from its group's shared deposit
// (made or read back once), and record it done or failed with its marker, a run of equal_time
// after its partner; the progress lines; the markers' timestamps.
#include "study/sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "core/interrupt.hpp"
#include "core/packing_io.hpp"
#include "core/settings_table.hpp"
#include "study/deposit_store.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The physical time a finished run spent in its fall (result.json's
// timing.stages.dynamic.simulated_time, the whole run on the dynamic protocol) [t0], which
// equal_time gives the runs of the other backend; throws when the result has none above zero.
double fallTime(const json& result) {
  static const json::json_pointer kFall("/timing/stages/dynamic/simulated_time");
  if (!result.contains(kFall) || !result.at(kFall).is_number() || !(result.at(kFall).get<double>() > 0.0))
    throw std::runtime_error("its result.json gives no fall time above zero (timing.stages.dynamic.simulated_time)");
  return result.at(kFall).get<double>();
}

// Serialises progress output of the workers: finished-run lines, and on a terminal one live line
// that is redrawn in place (carriage return + erase-line) with the state of the running runs.
class ProgressPrinter {
 public:
  ProgressPrinter(std::ostream& out, bool quiet, bool live) : out_(out), quiet_(quiet), live_(live) {}

  void finished(const std::string& line) {
    if (quiet_) return;
    std::lock_guard lock(mutex_);
    if (live_) out_ << "\r\033[K";
    out_ << line << '\n';
    drawLocked();
    out_.flush();
  }

  void update(const std::string& run, double fraction, const std::string& status) {
    if (quiet_ || !live_) return;
    std::lock_guard lock(mutex_);
    active_[run] = fmt::format("{} {:3.0f}% {}", run, 100.0 * std::clamp(fraction, 0.0, 1.0), status);
    const auto now = std::chrono::steady_clock::now();
    if (now - lastDraw_ < std::chrono::milliseconds(250)) return;  // a terminal needs no more
    lastDraw_ = now;
    drawLocked();
    out_.flush();
  }

  void remove(const std::string& run) {
    std::lock_guard lock(mutex_);
    active_.erase(run);
  }

 private:
  void drawLocked() {
    if (!live_ || active_.empty()) return;
    std::string line;
    for (const auto& [name, s] : active_) line += (line.empty() ? "" : " | ") + s;
    if (line.size() > 150) line.resize(150);
    out_ << "\r\033[K" << line;
  }

  std::ostream& out_;
  bool quiet_;
  bool live_;
  std::mutex mutex_;
  std::map<std::string, std::string> active_;
  std::chrono::steady_clock::time_point lastDraw_{};
};

// One deposit shared by the runs of its group: made or read back once, under the slot's lock, and
// released when the last run of the group in this task has finished.
struct DepositSlot {
  std::mutex mutex;
  std::shared_ptr<const compaction::Deposit> deposit;
  std::size_t remaining = 0;
};

}  // namespace

std::string utcTimestamp() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

namespace {

// What one run of the sweep came to: its result, or its error, or an interruption; t0 its start.
struct RunOutcome {
  json result;
  std::string error;
  bool interrupted = false;
  std::chrono::steady_clock::time_point t0;
};

// The workers of runSweep: each takes the next run of `todo`, claims it, runs it and records it
// done or failed, until none is left or a stop signal came. Verbs: work (the loop of a worker);
// the counts, read once all workers have ended.
class SweepWorkers {
 public:
  SweepWorkers(const std::vector<SweepRun>& runs, const std::vector<std::size_t>& todo,
               const std::vector<std::optional<std::size_t>>& partners, std::map<std::size_t, DepositSlot>& slots,
               const fs::path& dir, const std::vector<std::string>& varied, const SweepRunFn& run,
               const SweepDepositFn& makeDeposit, const LivenessFn& alive, ProgressPrinter& printer)
      : runs_(runs),
        todo_(todo),
        partners_(partners),
        inTodo_(runs.size(), false),
        ended_(std::make_unique<std::atomic<bool>[]>(runs.size())),
        slots_(slots),
        dir_(dir),
        varied_(varied),
        run_(run),
        makeDeposit_(makeDeposit),
        alive_(alive),
        printer_(printer),
        total_(todo.size()) {
    for (std::size_t i : todo) inTodo_[i] = true;
  }

  void work() {
    for (;;) {
      if (core::stopSignal() != 0) return;  // no new run after SIGINT/SIGTERM
      const std::size_t k = next_.fetch_add(1);
      if (k >= total_) return;
      const SweepRun& r = runs_[todo_[k]];
      // Another task may have been handed this run too (an array submitted again while one of its
      // tasks ran): only the holder of the run's claim works in its folder, and the claim is given
      // up when this iteration ends, marker written or interrupted.
      const std::optional<RunClaim> claim = claimRun(r);
      if (!claim) {
        ended_[r.index] = true;
        continue;
      }
      RunOutcome outcome = execute(r);
      release(r);
      const bool interrupted = outcome.interrupted;
      if (!interrupted) record(r, std::move(outcome));
      ended_[r.index] = true;  // after its marker: a run waiting for it finds the marker
      if (interrupted) return;
    }
  }

  std::atomic<std::size_t> finishedCount{0};
  std::atomic<std::size_t> failedCount{0};
  std::atomic<std::size_t> heldCount{0};           // claimed by another live process
  std::atomic<std::size_t> doneMeanwhileCount{0};  // finished by another process before we claimed it

 private:
  // The run's claim, or none (reported, and the run's deposit released) if another process holds
  // it, it cannot be taken, or the run was finished meanwhile.
  std::optional<RunClaim> claimRun(const SweepRun& r) {
    ClaimHolder holder;
    std::optional<RunClaim> claim;
    std::string claimError;
    try {
      claim = RunClaim::acquire(claimsDir(dir_), r.name, &holder, alive_);
    } catch (const std::exception& e) {
      claimError = e.what();
    }
    if (claim && runStatus(dir_ / "runs" / r.name) != RunStatus::Done) return claim;
    release(r);
    if (!claimError.empty()) {
      // No marker: the folder may be another process's.
      const std::size_t n = finishedCount.fetch_add(1) + 1;
      failedCount.fetch_add(1);
      printer_.finished(
          fmt::format("[{}/{}] {} {} FAILED: cannot claim it: {}", n, total_, r.name, r.config.backend, claimError));
    } else if (!claim) {
      heldCount.fetch_add(1);
      printer_.finished(fmt::format("{} {} skipped: {} runs it", r.name, r.config.backend, describe(holder)));
    } else {
      doneMeanwhileCount.fetch_add(1);
      printer_.finished(fmt::format("{} {} skipped: finished meanwhile by another task", r.name, r.config.backend));
    }
    return std::nullopt;
  }

  // With equal_time: the physical time of the fall of r's partner, once that run is done. Waits
  // while the partner is still to run, or running, in this process (partners are taken first); a
  // partner that failed, or that is neither done nor in this process's work, fails r, which a later
  // invocation redoes.
  double partnerFallTime(const SweepRun& r) {
    const SweepRun& p = runs_[*partners_[r.index]];
    const fs::path dir = dir_ / "runs" / p.name;
    for (;;) {
      const bool ended = ended_[p.index];  // read before the marker: a run ends after writing it
      const RunStatus status = runStatus(dir);
      if (status == RunStatus::Done) {
        try {
          return fallTime(core::readJsonFile(dir / "result.json", "result"));
        } catch (const std::exception& e) {
          throw std::runtime_error(fmt::format("equal_time: its {} run {}: {}", p.config.backend, p.name, e.what()));
        }
      }
      if (core::stopSignal() != 0)  // not a failure: r runs at the next invocation
        throw core::Interrupted(core::stopSignal(), fmt::format("while {} waited for {}", r.name, p.name));
      if (status == RunStatus::Failed || ended || !inTodo_[p.index])
        throw std::runtime_error(
            fmt::format("equal_time: its {} run {} {}", p.config.backend, p.name,
                        status == RunStatus::Failed ? "failed" : "has not finished: run it, then run this one again"));
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }

  // Runs `r` in a fresh folder with its config.json, from its group's deposit; with equal_time,
  // for its partner's fall time.
  RunOutcome execute(const SweepRun& r) {
    const fs::path runDir = dir_ / "runs" / r.name;
    RunOutcome out;
    out.t0 = std::chrono::steady_clock::now();
    try {
      // Anything left in an unfinished folder may be half written: start from nothing.
      fs::remove_all(runDir);
      fs::create_directories(runDir);
      core::RunConfig config = r.config;
      if (partners_[r.index]) config.compaction.timeLimit = partnerFallTime(r);
      json cfg;
      core::to_json(cfg, config);
      core::writeFileAtomically(runDir / "config.json", cfg.dump(2));
      const std::shared_ptr<const compaction::Deposit> deposit = depositFor(r);
      const std::string tag = fmt::format("{} {}", r.name, r.config.backend);
      out.result = run_(config, runDir, *deposit,
                        [&](double fraction, const std::string& status) { printer_.update(tag, fraction, status); });
      printer_.remove(tag);
    } catch (const core::Interrupted&) {
      // Not a failure: the run's folder has no marker, so the next invocation redoes it.
      out.interrupted = true;
    } catch (const std::exception& e) {
      out.error = e.what();
      if (out.error.empty()) out.error = "unknown error";
    } catch (...) {
      out.error = "unknown error";
    }
    return out;
  }

  // The run's marker (done.json, or failed.json) and its log line.
  void record(const SweepRun& r, RunOutcome outcome) {
    const fs::path runDir = dir_ / "runs" / r.name;
    const json& result = outcome.result;
    std::string& error = outcome.error;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - outcome.t0).count();
    const std::size_t n = finishedCount.fetch_add(1) + 1;
    const std::string w =
        r.config.box.periodicY ? "bi" + core::numberText(r.config.box.width) : core::numberText(r.config.box.width);
    // A run resumed from a checkpoint has run before: the marker and the log line give its
    // whole wall time, the earlier invocations' (up to their last checkpoint) and this one's.
    static const json::json_pointer kEarlier("/timing/checkpoint/earlier_s");
    const double earlier = result.is_object() && result.contains(kEarlier) && result.at(kEarlier).is_number()
                               ? result.at(kEarlier).get<double>()
                               : 0.0;
    const bool resumed = earlier > 0.0;
    const double runSeconds = seconds + earlier;
    if (error.empty()) error = writeDoneMarker(r, result, runSeconds, resumed ? std::optional(seconds) : std::nullopt);
    if (error.empty()) {
      std::string phi = "phi=?";
      if (result.contains("solid_fraction") && result.at("solid_fraction").is_number())
        phi = fmt::format("phi={:.3f}", result.at("solid_fraction").get<double>());
      const bool unequilibrated = result.contains("equilibrium") && result.at("equilibrium").is_object() &&
                                  result.at("equilibrium").value("reached", true) == false;
      printer_.finished(fmt::format("[{}/{}] {} {} W={} {} {:.0f} s{}{}", n, total_, r.name, r.config.backend, w, phi,
                                    runSeconds, resumed ? fmt::format(" ({:.0f} s since its resume)", seconds) : "",
                                    unequilibrated ? " (NOT equilibrated)" : ""));
      return;
    }
    failedCount.fetch_add(1);
    try {
      core::writeFileAtomically(runDir / kFailedMarker, json{{"name", r.name},
                                                             {"status", "failed"},
                                                             {"error", error},
                                                             {"wall_s", seconds},
                                                             {"finished", utcTimestamp()}}
                                                            .dump(2));
    } catch (...) {
      // The folder lacks done.json either way, so the next invocation redoes the run.
    }
    printer_.finished(fmt::format("[{}/{}] {} {} W={} FAILED after {:.0f} s: {}", n, total_, r.name, r.config.backend,
                                  w, seconds, error));
  }

  // The marker is the last thing written, atomically: its presence means result.json and
  // everything else of the run is complete. Returns the error of writing it, or nothing.
  std::string writeDoneMarker(const SweepRun& r, const json& result, double runSeconds,
                              std::optional<double> sinceResume) {
    json done = {{"name", r.name},
                 {"status", "done"},
                 {"wall_s", runSeconds},
                 {"finished", utcTimestamp()},
                 {"label", r.label(varied_)}};
    if (sinceResume) done["wall_s_since_resume"] = *sinceResume;
    if (result.contains("solid_fraction")) done["solid_fraction"] = result.at("solid_fraction");
    if (result.contains("equilibrium") && result.at("equilibrium").contains("reached"))
      done["equilibrium_reached"] = result.at("equilibrium").at("reached");
    try {
      core::writeFileAtomically(dir_ / "runs" / r.name / kDoneMarker, done.dump(2));
    } catch (const std::exception& e) {
      return fmt::format("cannot write {}: {}", kDoneMarker, e.what());
    }
    return {};
  }

  // The deposit of r's group: read back or made (and written) by its first run.
  std::shared_ptr<const compaction::Deposit> depositFor(const SweepRun& r) {
    DepositSlot& slot = slots_.at(r.depositIndex);
    std::lock_guard lock(slot.mutex);
    if (!slot.deposit) {
      const fs::path file = dir_ / "deposits" / (r.depositName() + ".json");
      if (fs::exists(file)) {
        slot.deposit = std::make_shared<const compaction::Deposit>(readDeposit(file));
      } else {
        auto made = std::make_shared<const compaction::Deposit>(makeDeposit_(r.config));
        writeDeposit(*made, r.config.box, file);
        slot.deposit = std::move(made);
      }
    }
    return slot.deposit;
  }

  void release(const SweepRun& r) {
    DepositSlot& slot = slots_.at(r.depositIndex);
    std::lock_guard lock(slot.mutex);
    if (--slot.remaining == 0) slot.deposit.reset();
  }

  const std::vector<SweepRun>& runs_;
  const std::vector<std::size_t>& todo_;
  const std::vector<std::optional<std::size_t>>& partners_;  // equal_time's, by run index
  std::vector<bool> inTodo_;                                 // by run index: in this process's work
  std::unique_ptr<std::atomic<bool>[]> ended_;               // by run index: its turn is over
  std::map<std::size_t, DepositSlot>& slots_;
  const fs::path& dir_;
  const std::vector<std::string>& varied_;
  const SweepRunFn& run_;
  const SweepDepositFn& makeDeposit_;
  const LivenessFn alive_;
  ProgressPrinter& printer_;
  const std::size_t total_;
  std::atomic<std::size_t> next_{0};
};

}  // namespace

SweepSummary runSweep(const SweepSpec& spec, const fs::path& dir, const SweepOptions& opt, const SweepRunFn& run,
                      const SweepDepositFn& makeDeposit) {
  if (opt.jobs < 1) throw std::invalid_argument(fmt::format("--jobs must be >= 1 (got {})", opt.jobs));
  const auto start = std::chrono::steady_clock::now();
  const std::vector<SweepRun> runs = expandRuns(spec);
  const std::vector<std::size_t> slice = opt.runs.empty() ? sliceRuns(runs, opt.taskIndex, opt.taskCount) : opt.runs;
  for (std::size_t i : slice)
    if (i >= runs.size()) throw std::invalid_argument(fmt::format("run index {} is not in the table", i));
  const std::vector<std::optional<std::size_t>> partners = equalTimePartners(runs, spec.equalTime);
  prepareSweepDir(dir, spec, runs);
  const std::vector<std::string> varied = variedSettings(runs);

  SweepSummary summary;
  summary.total = runs.size();
  summary.inSlice = slice.size();

  std::vector<std::size_t> todo;
  std::map<std::size_t, DepositSlot> slots;
  for (std::size_t i : slice) {
    if (runStatus(dir / "runs" / runs[i].name) == RunStatus::Done) {
      ++summary.alreadyDone;
      continue;
    }
    todo.push_back(i);
    ++slots[runs[i].depositIndex].remaining;
  }
  // equal_time's partners first, so that no run waits for one that no worker has taken yet.
  std::stable_partition(todo.begin(), todo.end(), [&](std::size_t i) { return !partners[i]; });

  std::ostream& log = opt.log ? *opt.log : std::cerr;
  ProgressPrinter printer(log, opt.quiet, opt.live);
  if (!opt.quiet)
    printer.finished(fmt::format("sweep {}: {} runs, {} in this task ({}/{}), {} already done, {} to run with {} job{}",
                                 spec.name, runs.size(), slice.size(), opt.taskIndex, opt.taskCount,
                                 summary.alreadyDone, todo.size(), opt.jobs, opt.jobs > 1 ? "s" : ""));

  const LivenessFn alive = opt.alive ? opt.alive : LivenessFn(holderLiveness);
  const std::size_t total = todo.size();
  SweepWorkers workers(runs, todo, partners, slots, dir, varied, run, makeDeposit, alive, printer);
  {
    std::vector<std::jthread> pool;
    const int count =
        static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(opt.jobs), std::max<std::size_t>(total, 1)));
    for (int i = 1; i < count; ++i) pool.emplace_back([&workers] { workers.work(); });
    workers.work();  // the calling thread is one of the workers
  }

  const std::size_t finishedCount = workers.finishedCount.load();
  if (core::stopSignal() != 0 && finishedCount + workers.heldCount.load() + workers.doneMeanwhileCount.load() < total)
    throw core::Interrupted(
        core::stopSignal(),
        fmt::format("after {} of {} runs; the others run when the sweep is started again", finishedCount, total));
  summary.failed = workers.failedCount.load();
  summary.ran = finishedCount - summary.failed;
  summary.heldElsewhere = workers.heldCount.load();
  summary.alreadyDone += workers.doneMeanwhileCount.load();
  summary.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!opt.quiet)
    printer.finished(fmt::format(
        "sweep {}: {} finished, {} failed, {} skipped (already done){} in {:.0f} s", spec.name, summary.ran,
        summary.failed, summary.alreadyDone,
        summary.heldElsewhere > 0 ? fmt::format(", {} left to other live tasks", summary.heldElsewhere) : std::string(),
        summary.wallSeconds));
  return summary;
}

}  // namespace confpack::study
