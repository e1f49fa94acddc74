#include "study/sweep.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "backends/backend_factory.hpp"
#include "core/backend.hpp"
#include "core/interrupt.hpp"
#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "core/settings_table.hpp"
#include "study/deposit_store.hpp"
#include "study/sweep_internal.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json runTableJson(const std::vector<SweepRun>& runs) {
  json table = json::array();
  const std::vector<std::string> varied = variedSettings(runs);
  for (const SweepRun& r : runs) {
    json cfg;
    core::to_json(cfg, r.config);
    table.push_back({{"name", r.name}, {"deposit", r.depositName()}, {"label", r.label(varied)}, {"config", cfg}});
  }
  return table;
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

std::string_view toString(RunStatus s) {
  switch (s) {
    case RunStatus::Pending:
      return "pending";
    case RunStatus::Incomplete:
      return "incomplete";
    case RunStatus::Failed:
      return "failed";
    case RunStatus::Done:
      return "done";
  }
  return "?";
}

RunStatus runStatus(const fs::path& runDir) {
  if (fs::exists(runDir / kDoneMarker)) return RunStatus::Done;
  if (fs::exists(runDir / kFailedMarker)) return RunStatus::Failed;
  if (fs::exists(runDir)) return RunStatus::Incomplete;
  return RunStatus::Pending;
}

void prepareSweepDir(const fs::path& dir, const SweepSpec& spec, const std::vector<SweepRun>& runs) {
  fs::create_directories(dir / "runs");
  fs::create_directories(dir / "deposits");
  const json table = runTableJson(runs);
  const fs::path tablePath = dir / kSweepTable;
  if (fs::exists(tablePath)) {
    const json existing = core::readJsonFile(tablePath, "sweep table");
    // Run by run, each stored configuration as the reader reads it, so that a table written by an
    // earlier version in another spelling (mu_w as box.wall_friction) still resumes; nothing of
    // the stored document is copied (a hand-edited value may be nested too deep for that).
    const auto sameRun = [](const json& stored, const json& expected) {
      if (!stored.is_object() || stored.size() != expected.size()) return false;
      for (const auto& [key, value] : expected.items()) {
        if (!stored.contains(key)) return false;
        if (key != "config") {
          if (stored.at(key) != value) return false;
          continue;
        }
        try {
          if (json(stored.at(key).get<core::RunConfig>()) != value) return false;
        } catch (const std::exception&) {
          return false;
        }
      }
      return true;
    };
    const auto sameTable = [&](const json& stored) {
      if (!stored.is_array() || stored.size() != table.size()) return false;
      for (std::size_t i = 0; i < table.size(); ++i)
        if (!sameRun(stored[i], table[i])) return false;
      return true;
    };
    if (!existing.contains("runs") || !sameTable(existing.at("runs")))
      throw std::invalid_argument(
          fmt::format("{}: holds a different sweep (its run table differs from this sweep file's); resume it with the "
                      "sweep file that made it, or choose a new output folder",
                      dir.string()));
    return;
  }
  // Several tasks of a job array may get here at once: each writes the same bytes atomically.
  core::writeFileAtomically(tablePath, runTableDocument(spec, runs).dump(1));
}

json runTableDocument(const SweepSpec& spec, const std::vector<SweepRun>& runs) {
  return {{"format", kSweepTableFormat},
          {"version", 1},
          {"name", spec.name},
          {"sweep", spec.source},
          {"runs", runTableJson(runs)}};
}

std::vector<SweepRun> parseRunTable(const json& doc, std::string_view source, SweepSpec* spec) {
  if (!doc.is_object()) bad(source, "(document)", "expected a JSON object");
  for (const auto& [key, v] : doc.items())
    if (key != "format" && key != "version" && key != "name" && key != "sweep" && key != "runs")
      bad(source, core::textExcerpt(key), "unknown key (known: format, version, name, sweep, runs)");
  if (!doc.contains("format") || doc.at("format") != kSweepTableFormat)
    bad(source, "format", fmt::format("not a confpack sweep table (expected \"{}\")", kSweepTableFormat));
  if (doc.contains("version") && doc.at("version") != 1) bad(source, "version", "expected 1");
  if (!doc.contains("runs") || !doc.at("runs").is_array()) bad(source, "runs", "expected an array (the run table)");
  if (!doc.contains("sweep")) bad(source, "sweep", "missing (the sweep file that made the table)");
  const json& table = doc.at("runs");
  // The table on disk was listed already, under whatever --max-runs its sweep was given.
  SweepSpec parsed =
      parseSweepSpec(doc.at("sweep"), fmt::format("{}: sweep", source), std::max(kDefaultMaxRuns, table.size()));
  // A user may edit the table: every field is checked, and a name must stay one folder of runs/.
  std::vector<SweepRun> runs;
  std::set<std::string> names;
  for (const json& r : table) {
    const std::string where = fmt::format("runs[{}]", runs.size());
    if (!r.is_object()) bad(source, where, "expected an object (name, deposit, label, config)");
    for (const auto& [key, v] : r.items())
      if (key != "name" && key != "deposit" && key != "label" && key != "config")
        bad(source, fmt::format("{}.{}", where, core::textExcerpt(key)),
            "unknown key (known: name, deposit, label, config)");
    for (const char* key : {"name", "deposit", "config"})
      if (!r.contains(key)) bad(source, fmt::format("{}.{}", where, key), "missing");
    SweepRun run;
    run.index = runs.size();
    const json& name = r.at("name");
    if (!name.is_string() || name.get<std::string>().empty() || name.get<std::string>().size() > 64 ||
        name.get<std::string>().find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
            std::string::npos)
      bad(source, where + ".name",
          fmt::format("expected a run folder's name: letters, digits, '_' or '-' (got {})", core::jsonExcerpt(name)));
    run.name = name.get<std::string>();
    if (!names.insert(run.name).second) bad(source, where + ".name", fmt::format("\"{}\" names two runs", run.name));
    const json& deposit = r.at("deposit");
    const std::string dep = deposit.is_string() ? deposit.get<std::string>() : std::string();
    if (dep.size() < 2 || dep.size() > 10 || dep[0] != 'd' ||
        dep.find_first_not_of("0123456789", 1) != std::string::npos || std::stoul(dep.substr(1)) >= table.size())
      bad(source, where + ".deposit",
          fmt::format("expected \"d\" and the index of a deposit below the number of runs (got {})",
                      core::jsonExcerpt(deposit)));
    run.depositIndex = static_cast<std::size_t>(std::stoul(dep.substr(1)));
    try {
      core::from_json(r.at("config"), run.config);
      run.config.validate();
    } catch (const std::invalid_argument& e) {
      bad(source, where + ".config", e.what());
    } catch (const json::exception& e) {
      bad(source, where + ".config", e.what());
    }
    runs.push_back(std::move(run));
  }
  if (spec) *spec = std::move(parsed);
  return runs;
}

std::vector<SweepRun> readRunTable(const fs::path& dir, SweepSpec* spec) {
  const fs::path tablePath = dir / kSweepTable;
  if (!fs::exists(tablePath))
    throw std::invalid_argument(fmt::format("{}: not a sweep folder (no {})", dir.string(), kSweepTable));
  return parseRunTable(core::readJsonFile(tablePath, "sweep table"), tablePath.string(), spec);
}

std::string formatRunTable(const std::vector<SweepRun>& runs, const fs::path& dir, std::optional<std::size_t> taskIndex,
                           std::size_t taskCount) {
  std::set<std::size_t> slice;
  if (taskIndex)
    for (std::size_t i : sliceRuns(runs, *taskIndex, taskCount)) slice.insert(i);
  // A column per varied setting, as wide as its name or its widest value.
  const std::vector<std::string> varied = variedSettings(runs);
  const std::vector<std::string> names = settingNames(varied);
  std::vector<std::vector<std::string>> cells(runs.size());
  std::vector<std::size_t> widths;
  for (const std::string& n : names) widths.push_back(n.size());
  for (std::size_t k = 0; k < runs.size() && !varied.empty(); ++k) {
    json cfg;
    core::to_json(cfg, runs[k].config);
    for (std::size_t i = 0; i < varied.size(); ++i) {
      cells[k].push_back(settingText(cfg, varied[i]));
      widths[i] = std::max(widths[i], cells[k].back().size());
    }
  }
  std::ostringstream out;
  out << fmt::format("{:<7} {:<7} {:<6} {:>5} {:>8} {:>5} {:>6} {:<7}", "run", "deposit", "family", "x_S", "W", "mu_w",
                     "seed", "backend");
  for (std::size_t i = 0; i < names.size(); ++i) out << fmt::format(" {:<{}}", names[i], widths[i]);
  out << (dir.empty() ? "" : " status") << '\n';
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const SweepRun& r = runs[k];
    if (taskIndex && !slice.count(r.index)) continue;
    const std::string w = r.config.box.periodicY ? fmt::format("bi{}", core::numberText(r.config.box.width))
                                                 : core::numberText(r.config.box.width);
    out << fmt::format("{:<7} {:<7} {:<6} {:>5} {:>8} {:>5} {:>6} {:<7}", r.name, r.depositName(), familyName(r.config),
                       core::numberText(r.config.population.smallFraction), w,
                       core::numberText(r.config.walls.friction), r.config.seed, r.config.backend);
    for (std::size_t i = 0; i < varied.size(); ++i) out << fmt::format(" {:<{}}", cells[k][i], widths[i]);
    if (!dir.empty()) out << ' ' << toString(runStatus(dir / "runs" / r.name));
    out << '\n';
  }
  return out.str();
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
               std::map<std::size_t, DepositSlot>& slots, const fs::path& dir, const std::vector<std::string>& varied,
               const SweepRunFn& run, const SweepDepositFn& makeDeposit, const LivenessFn& alive,
               ProgressPrinter& printer)
      : runs_(runs),
        todo_(todo),
        slots_(slots),
        dir_(dir),
        varied_(varied),
        run_(run),
        makeDeposit_(makeDeposit),
        alive_(alive),
        printer_(printer),
        total_(todo.size()) {}

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
      if (!claim) continue;
      RunOutcome outcome = execute(r);
      release(r);
      if (outcome.interrupted) return;
      record(r, std::move(outcome));
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

  // Runs `r` in a fresh folder with its config.json, from its group's deposit.
  RunOutcome execute(const SweepRun& r) {
    const fs::path runDir = dir_ / "runs" / r.name;
    RunOutcome out;
    out.t0 = std::chrono::steady_clock::now();
    try {
      // Anything left in an unfinished folder may be half written: start from nothing.
      fs::remove_all(runDir);
      fs::create_directories(runDir);
      json cfg;
      core::to_json(cfg, r.config);
      core::writeFileAtomically(runDir / "config.json", cfg.dump(2));
      const std::shared_ptr<const compaction::Deposit> deposit = depositFor(r);
      const std::string tag = fmt::format("{} {}", r.name, r.config.backend);
      out.result = run_(r.config, runDir, *deposit,
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

  std::ostream& log = opt.log ? *opt.log : std::cerr;
  ProgressPrinter printer(log, opt.quiet, opt.live);
  if (!opt.quiet)
    printer.finished(fmt::format("sweep {}: {} runs, {} in this task ({}/{}), {} already done, {} to run with {} job{}",
                                 spec.name, runs.size(), slice.size(), opt.taskIndex, opt.taskCount,
                                 summary.alreadyDone, todo.size(), opt.jobs, opt.jobs > 1 ? "s" : ""));

  const LivenessFn alive = opt.alive ? opt.alive : LivenessFn(holderLiveness);
  const std::size_t total = todo.size();
  SweepWorkers workers(runs, todo, slots, dir, varied, run, makeDeposit, alive, printer);
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
