#pragma once
// Sweeps (docs/model.md, "The study and its report"): a base run configuration and lists of values
// to combine (width W or biperiodic, shape, x_S, mu_w, seeds, backends, and any other key of the
// run configuration by its path, e.g. "population.pinacoid.alpha_deg"), expanded into a table of
// runs with stable names r0000, r0001, ... that are run locally in parallel or sliced over the
// tasks of a cluster job array, and that resume after an interruption without redoing a finished
// run.
//
// Folder layout of a sweep (docs/sweeps.md has the full description):
//   SWEEPDIR/sweep.json            the sweep file as given + the expanded run table
//   SWEEPDIR/deposits/d0000.json   one deposit per (box, population, deposition, seed)
//   SWEEPDIR/runs/r0000/           config.json, result.json, profiles, packing, frames, and
//                                  done.json (written last, atomically) or failed.json
//   SWEEPDIR/claims/r0000          while a process runs r0000: who (study/run_claim.hpp)
// A run folder without done.json is not finished: it is wiped and redone from scratch.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "compaction/deposition.hpp"
#include "core/run_config.hpp"
#include "study/run_claim.hpp"
#include "study/run_pipeline.hpp"

namespace confpack::study {

/// Value of the "format" key of a sweep file.
inline constexpr std::string_view kSweepFormat = "confpack-sweep";
inline constexpr int kSweepVersion = 1;

/// One confinement: side walls a gap `width` apart, or biperiodic with period `width`.
struct WidthChoice {
  double width = 10.0;     ///< [d_L]
  bool periodicY = false;  ///< true: the unconfined (biperiodic) reference
  bool operator==(const WidthChoice&) const = default;
};

/// A sweep axis named by its path in the run configuration, the keys of config.json joined by '.'
/// ("population.pinacoid.alpha_deg", "compaction.protocol", "backend_options.tolerance"): each run
/// of the axis has one of the values at that path. The path and every value were checked against
/// the configuration's readers when the sweep file was parsed.
struct SettingAxis {
  std::string path;
  std::vector<nlohmann::json> values;
};

/// One cartesian product of values; an empty list means "the base configuration's value".
struct SweepGroup {
  std::vector<WidthChoice> widths;
  std::vector<core::ShapeKind> shapes;
  std::vector<double> smallFractions;  ///< x_S [% by volume]
  std::vector<double> wallFrictions;   ///< mu_w [-]
  std::vector<std::uint64_t> seeds;
  std::vector<std::string> backends;
  std::vector<SettingAxis> settings;  ///< every other key of the group, in the order of their paths
};

/// A parsed, validated sweep file.
struct SweepSpec {
  std::string name = "sweep";
  nlohmann::json base = nlohmann::json::object();  ///< partial RunConfig JSON over the defaults
  double biperiodicWidth = 20.0;                   ///< period of "biperiodic" entries [d_L]
  std::vector<SweepGroup> groups;
  /// "settle_with": a backend with a quasi-static finisher ("nscd") that takes every finished run of
  /// another backend on to rest from its final packing, kept beside it in RUN/settled/
  /// (docs/sweeps.md); empty: none.
  std::string settleWith;
  /// "equal_time": a backend ("nscd") whose fall sets the time of the other backends' runs: each of
  /// them runs for the physical time the fall of its partner took (equalTimePartners), in place of
  /// its compaction.time_limit (docs/sweeps.md); empty: none.
  std::string equalTime;
  nlohmann::json source;  ///< the document as given (kept in sweep.json)
};

/// One run of the table.
struct SweepRun {
  std::size_t index = 0;         ///< position in the run table
  std::string name;              ///< "r0007": the folder name, never a float value
  std::size_t depositIndex = 0;  ///< runs with the same index compact the same deposit
  core::RunConfig config;        ///< fully resolved

  /// "d0003": the deposit file stem.
  std::string depositName() const;
  /// Short human label, e.g. "MSP xS=0 W=10 mu=0.3 s1 nscd", followed by the value of each of
  /// `settings` (configuration paths, variedSettings) under its short name: " alpha_deg=45 E=0.5".
  std::string label(const std::vector<std::string>& settings = {}) const;
};

/// The settings a run table and a report show beside W, shape, x_S, mu_w, seed and backend: the
/// paths of the run configuration whose values differ between the runs (a sweep's setting axes),
/// in path order. Empty for a sweep over those named axes alone.
std::vector<std::string> variedSettings(const std::vector<SweepRun>& runs);

/// The value at `path` (keys joined by '.') of a configuration written as JSON, null where it has
/// none.
const nlohmann::json* settingAt(const nlohmann::json& cfg, const std::string& path);

/// The value at `path` of a configuration as text ("45", "quasi-static"), "-" where it has none
/// (a backend option the run does not set).
std::string settingText(const core::RunConfig& cfg, const std::string& path);
/// The same of a configuration written as JSON (core::to_json).
std::string settingText(const nlohmann::json& cfg, const std::string& path);

/// Names for configuration paths, as short as stays unambiguous: the last key ("alpha_deg"), or
/// the last two ("pinacoid.E") and so on where two paths end alike.
std::vector<std::string> settingNames(const std::vector<std::string>& paths);

/// Most runs a sweep file may list unless `confpack sweep --max-runs` raises the limit
/// (docs/sweeps.md). The paper-scale study has 174 runs; a table of 100,000 takes 0.22 GB and 5 s
/// to list (measured with --list), while a typo such as "replicas": 100000000 would need tens of
/// gigabytes.
inline constexpr std::size_t kDefaultMaxRuns = 100000;

/// Validates a sweep document; throws std::invalid_argument naming `source` and the bad field,
/// and refuses, before listing any run, a document whose groups list more than `maxRuns` runs
/// (the product of each group's list sizes, summed over the groups: duplicates counted).
SweepSpec parseSweepSpec(const nlohmann::json& doc, std::string_view source = "sweep",
                         std::size_t maxRuns = kDefaultMaxRuns);
/// Reads and parses a sweep file (JSON).
SweepSpec readSweepSpec(const std::filesystem::path& path, std::size_t maxRuns = kDefaultMaxRuns);

/// Expands the groups in order (shape, x_S, W, mu_w, the setting axes in the order of their paths,
/// seed, backend; backend varies fastest), drops
/// duplicates of runs already in the table, and gives each run its stable name and its deposit.
/// Each resolved configuration is validated (std::invalid_argument names the run).
std::vector<SweepRun> expandRuns(const SweepSpec& spec);

/// With a sweep's equal_time `backend`: for each run of the table, the index of its partner, the
/// first run of `backend` with the same configuration (deposit included) whatever the backend
/// options and compaction.time_limit; none for the runs of `backend` themselves, and for every run
/// when `backend` is empty. Throws std::invalid_argument naming the first run that has no partner.
std::vector<std::optional<std::size_t>> equalTimePartners(const std::vector<SweepRun>& runs,
                                                          const std::string& backend);

/// Short name of a configuration's family: MSP, BSP, MPP, BPP (docs/model.md, "Mixtures").
std::string familyName(const core::RunConfig& cfg);

/// Runs of one task of a job array: deposit groups are dealt round-robin over the tasks (group g
/// goes to task g mod taskCount), so every run belongs to exactly one task and the runs sharing a
/// deposit stay together (the deposit is computed once). Returns run indices in table order.
std::vector<std::size_t> sliceRuns(const std::vector<SweepRun>& runs, std::size_t taskIndex, std::size_t taskCount);

enum class RunStatus { Pending, Incomplete, Failed, Done };
std::string_view toString(RunStatus s);

/// State of a run folder: Done when done.json exists, Failed when failed.json exists, Incomplete
/// when the folder exists without either marker, Pending when there is no folder.
RunStatus runStatus(const std::filesystem::path& runDir);

inline constexpr const char* kDoneMarker = "done.json";
inline constexpr const char* kFailedMarker = "failed.json";
inline constexpr const char* kSweepTable = "sweep.json";

/// A sweep run's checkpoint: SWEEPDIR/checkpoints/rNNNN.json, outside the run's folder, which a
/// new attempt clears.
inline std::filesystem::path sweepCheckpointFile(const std::filesystem::path& sweepDir, const std::string& run) {
  return sweepDir / "checkpoints" / (run + ".json");
}

/// Where a run with a settle (settle_with) keeps its own finished folder until the settle is done:
/// SWEEPDIR/checkpoints/rNNNN-unsettled/ (study/sweep_runner.hpp, runOrRestore).
inline std::filesystem::path sweepKeptRunFolder(const std::filesystem::path& sweepDir, const std::string& run) {
  return sweepDir / "checkpoints" / (run + "-unsettled");
}

/// The checkpoint of a run's settle: SWEEPDIR/checkpoints/rNNNN-settled.json.
inline std::filesystem::path sweepSettleCheckpointFile(const std::filesystem::path& sweepDir, const std::string& run) {
  return sweepCheckpointFile(sweepDir, run + "-settled");
}

/// The time now in UTC, ISO 8601 ("2024-05-01T12:00:00Z"), as the markers record it.
std::string utcTimestamp();

/// Compacts `deposit` with cfg in runDir (which exists and is empty) and returns result.json's
/// content; it must have written result.json before returning. The real one is runAndWrite.
using SweepRunFn = std::function<nlohmann::json(const core::RunConfig& cfg, const std::filesystem::path& runDir,
                                                const compaction::Deposit& deposit, const RunProgressFn& progress)>;
/// Makes the deposit of a configuration (the real one is compaction::deposit with cfg's seed).
using SweepDepositFn = std::function<compaction::Deposit(const core::RunConfig& cfg)>;

struct SweepOptions {
  int jobs = 1;                   ///< runs at the same time in this process
  std::size_t taskIndex = 0;      ///< this task's slice, in [0, taskCount)
  std::size_t taskCount = 1;      ///< number of tasks sharing the sweep
  std::vector<std::size_t> runs;  ///< when not empty: these runs (indices in the table) instead of the slice
  LivenessFn alive;               ///< judges the holder of a run's claim; empty = holderLiveness
  bool quiet = false;             ///< no progress lines
  std::ostream* log = nullptr;    ///< progress stream; nullptr = std::cerr
  bool live = false;              ///< redraw a live status line (only on a terminal)
};

struct SweepSummary {
  std::size_t total = 0;          ///< runs in the table
  std::size_t inSlice = 0;        ///< runs of this task
  std::size_t alreadyDone = 0;    ///< found finished and skipped
  std::size_t ran = 0;            ///< finished now
  std::size_t failed = 0;         ///< threw; failed.json written, retried by the next invocation
  std::size_t heldElsewhere = 0;  ///< claimed by another live process (study/run_claim.hpp): left to it
  double wallSeconds = 0.0;
};

/// Creates SWEEPDIR and writes sweep.json, or, when SWEEPDIR already holds a sweep, checks that its
/// run table is the same (std::invalid_argument otherwise: a different sweep needs a new folder).
void prepareSweepDir(const std::filesystem::path& dir, const SweepSpec& spec, const std::vector<SweepRun>& runs);

/// Runs this task's unfinished runs with `opt.jobs` workers. A run that throws is recorded in
/// failed.json and the sweep goes on. Deposits are made (or read back) once per deposit group.
/// Each run is claimed first (SWEEPDIR/claims, study/run_claim.hpp): a run another live process
/// holds is left to it, so that two tasks handed the same run never write its folder at once.
SweepSummary runSweep(const SweepSpec& spec, const std::filesystem::path& dir, const SweepOptions& opt,
                      const SweepRunFn& run, const SweepDepositFn& makeDeposit);

/// The run table as text (name, deposit, family, x_S, W, mu_w, seed, backend, a column per varied
/// setting, status when `dir` is given), one line per run, for `confpack sweep --list`.
std::string formatRunTable(const std::vector<SweepRun>& runs, const std::filesystem::path& dir = {},
                           std::optional<std::size_t> taskIndex = {}, std::size_t taskCount = 1);

/// The format name of SWEEPDIR/sweep.json.
inline constexpr std::string_view kSweepTableFormat = "confpack-sweep-table";

/// SWEEPDIR/sweep.json's document: the sweep file as given (spec.source) and the run table.
nlohmann::json runTableDocument(const SweepSpec& spec, const std::vector<SweepRun>& runs);

/// The run table of a sweep.json document, `source` naming it in messages. sweep.json is written
/// by confpack but a user may edit it: every field is checked (the sweep file it holds, each run's
/// name, a folder name used once, its deposit, its configuration, validated), and a bad one is
/// refused with std::invalid_argument "SOURCE: runs[3].deposit: ...". `spec`, if given, receives
/// the parsed sweep file.
std::vector<SweepRun> parseRunTable(const nlohmann::json& doc, std::string_view source, SweepSpec* spec = nullptr);

/// Reads the run table back from SWEEPDIR/sweep.json (for the report): parseRunTable of the file.
std::vector<SweepRun> readRunTable(const std::filesystem::path& dir, SweepSpec* spec = nullptr);

}  // namespace confpack::study
