#pragma once
// What the subcommands share: the common flags (README, "Command line") bound into a
// core::RunConfig, the exit-code discipline, and all-or-nothing output directories.
//
// Exit codes: 0 ok, 2 bad input (refused before any work, nothing written), 1 runtime failure
// (nothing partial left behind; running out of memory included), 128 + signal when SIGINT or
// SIGTERM stopped the work. Every failure prints exactly one line on stderr.
#include <exception>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "core/packing.hpp"
#include "core/run_config.hpp"

namespace CLI {
class App;
class Option;
class Validator;
}  // namespace CLI

namespace confpack::app {

inline constexpr int kExitOk = 0;
inline constexpr int kExitRuntimeFailure = 1;
inline constexpr int kExitBadInput = 2;

/// Flags that are not part of the run configuration.
struct CommonOptions {
  std::filesystem::path out;  ///< --out DIR
  bool quiet = false;         ///< --quiet: no progress, summary only
  int verbosity = 0;          ///< -v (repeatable): more detail on stderr
};

/// Adds the common flags to a subcommand: --shape, --length-x, --width, --periodic-y,
/// --height, --small-fraction, --wall-friction, --backend, --seed, --out, --threads, --quiet, -v,
/// plus --pinacoid-G, --pinacoid-E, --pinacoid-alpha. Values land in `cfg` and `opts`, with
/// validators so that a bad value is refused by the parser, before any work. The defaults shown
/// by --help are those of the core definition structs.
void addRunConfigOptions(CLI::App& sub, core::RunConfig& cfg, CommonOptions& opts, bool outRequired = true);

/// `--protocol dynamic|quasi-static` (docs/model.md, "Protocols") into `protocol`.
CLI::Option* addProtocolOption(CLI::App& sub, core::Protocol& protocol);

/// Validators for real-valued flags with one readable message ("--width: must be a positive number
/// (got -3)"). CLI11's PositiveNumber/Range print their bounds as 300-digit numbers and accept
/// "inf"; use these instead. realIn: a finite real in [lo, hi] (open ends when loOpen/hiOpen).
CLI::Validator realIn(double lo, double hi, bool loOpen, bool hiOpen, const std::string& what,
                      const std::string& typeName);
CLI::Validator positiveNumber();     ///< finite, > 0
CLI::Validator nonNegativeNumber();  ///< finite, >= 0
CLI::Validator unsignedInteger();    ///< digits only (CLI11 wraps "-1" to 2^64 - 1 for unsigned)

/// The CLI11 failure message of `confpack`: one line, "confpack: error: <what> (see --help)".
std::string oneLineFailure(const CLI::App* app, const std::exception& e);

/// Parses the command line and runs the chosen callbacks; returns the exit code: 0 (help
/// included), the code of a RuntimeError the work raised, kExitRuntimeFailure with the line
/// "<program> <command>: out of memory while <step>" for a std::bad_alloc from anywhere (parsing,
/// input checks or work; see WorkStep), or kExitBadInput for every other parse failure (unknown
/// flag, bad value, missing --out), whatever CLI11's own numbering says.
int parseAndRun(CLI::App& app, int argc, char** argv);

/// Names what the current thread is doing, for the out-of-memory line of parseAndRun ("confpack
/// deposit: out of memory while writing packing.json"). `what` must be a string literal: the line is
/// written without allocating, once the memory has run out. A scope left by an exception keeps its
/// step, so that the line names the innermost step where the allocation failed.
class WorkStep {
 public:
  explicit WorkStep(const char* what) noexcept;
  ~WorkStep();
  /// The scope has moved on to its next step.
  void next(const char* what) noexcept;
  WorkStep(const WorkStep&) = delete;
  WorkStep& operator=(const WorkStep&) = delete;

 private:
  const char* previous_;
  int uncaught_;  ///< std::uncaught_exceptions() at construction: more at destruction = unwinding
};

/// Runs input checks of subcommand `command` (a string literal; empty for a program without
/// subcommands): a std::exception becomes one line "<program> <command>: error: <what>" and exit
/// code 2 (CLI::RuntimeError); <program> is the name of the app parseAndRun ran. std::bad_alloc
/// is not bad input: it goes on to parseAndRun (exit 1); nor is core::Interrupted (exit 128 + its
/// signal).
void checkInput(std::string_view command, const std::function<void()>& checks);
/// Runs the work of a subcommand: any std::exception becomes one line and exit code 1;
/// core::Interrupted exit code 128 + its signal; std::bad_alloc goes on to parseAndRun.
void runWork(std::string_view command, const std::function<void()>& work);

/// `--allow-implausible` into `allow`: a packing file analysis/plausibility.hpp finds implausible is
/// taken anyway.
CLI::Option* addAllowImplausibleFlag(CLI::App& sub, bool& allow);
/// The file confpack writes into every output folder it commits (StagedOutput): a folder that
/// holds it is confpack's own, which a later command may replace.
inline constexpr const char* kOutputMarker = ".confpack-output";
/// Refuses, as bad input, an --out that confpack may not write into. It must be a new folder (not
/// existing yet), an empty folder, or a folder confpack wrote (it holds kOutputMarker): replacing
/// or filling anything else (the filesystem root, a home folder, a file) would destroy or mix in
/// files that are not confpack's. The message names the path and why.
void checkOutputTarget(const std::filesystem::path& out);
/// Creates folder `dir` if needed and puts kOutputMarker in it, for a folder confpack fills itself
/// rather than through StagedOutput (a sweep's or a study's folder).
void markOutputFolder(const std::filesystem::path& dir);

/// Applies --threads to OpenMP (when the build has it).
void applyThreads(int threads);

/// An output directory that appears complete or not at all. Files are written into a hidden
/// staging directory next to the target (same file system, so renames are atomic); commit() moves
/// them in place: the whole directory in one rename when the target does not exist yet, else entry
/// by entry, each old entry first moved aside into the staging directory. When a rename fails
/// midway, commit() moves the new entries back out and the old ones back in before it throws: the
/// target then holds its old files, none of the new ones. Once every new entry is in place the
/// output is committed: an old entry that then cannot be removed is a warning (warning()), not a
/// failure. Without commit() (an exception unwinds), the staging directory and any parent
/// directories created for it are removed. The staging directory holds kOutputMarker from the
/// start, so that every committed output carries it.
class StagedOutput {
 public:
  /// How an entry is moved (std::filesystem::rename; a test injects failures).
  using RenameFn = std::function<void(const std::filesystem::path& from, const std::filesystem::path& to)>;
  /// How the replaced old entries are removed after the commit (std::filesystem::remove_all; a
  /// test injects a failure, as an immutable file gives).
  using RemoveFn = std::function<void(const std::filesystem::path& path)>;

  /// Throws std::runtime_error "cannot create output folder TARGET: <reason>" when the staging
  /// directory cannot be made next to `target` (a read-only file system, /proc).
  explicit StagedOutput(const std::filesystem::path& target, RenameFn rename = {}, RemoveFn removeAll = {});
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  /// Where to write.
  const std::filesystem::path& dir() const { return staging_; }
  /// Removes the staging folder and the parents made for it, if it can (never throws): on a
  /// failure, and at once for a process about to end without unwinding (out of memory where no
  /// exception may leave).
  void discardStaging() noexcept;
  /// The final directory.
  const std::filesystem::path& target() const { return target_; }
  void commit();
  /// After commit(): the warning line it wrote on stderr when the old files it replaced could not
  /// be removed (it names the folder they are left in), else empty.
  const std::string& warning() const { return warning_; }

 private:
  std::filesystem::path target_;
  std::filesystem::path staging_;
  std::vector<std::filesystem::path> createdParents_;  ///< deepest first
  RenameFn rename_;
  RemoveFn removeAll_;
  std::string warning_;
  bool committed_ = false;
  bool keepStaging_ = false;  ///< a failed commit could not put the old files back: they are in it
};

/// Writes `j` (indented) to `path` atomically.
void writeJson(const std::filesystem::path& path, const nlohmann::json& j);

}  // namespace confpack::app
