#include "apps/cli_common.hpp"

#include <dirent.h>
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <system_error>
#include <utility>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "backends/backend_factory.hpp"
#include "core/interrupt.hpp"
#include "core/packing_io.hpp"

namespace confpack::app {

namespace fs = std::filesystem;

CLI::Validator realIn(double lo, double hi, bool loOpen, bool hiOpen, const std::string& what,
                      const std::string& typeName) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        char* end = nullptr;
        errno = 0;
        const double x = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(x))
          return fmt::format("must be {} (got '{}', not a finite number)", what, text);
        const bool ok = (loOpen ? x > lo : x >= lo) && (hiOpen ? x < hi : x <= hi);
        return ok ? std::string() : fmt::format("must be {} (got {})", what, text);
      },
      typeName);
}

CLI::Validator positiveNumber() {
  return realIn(0.0, HUGE_VAL, true, true, "a positive number", "POSITIVE");
}

CLI::Validator nonNegativeNumber() {
  return realIn(0.0, HUGE_VAL, false, true, "a number >= 0", "NON-NEGATIVE");
}

CLI::Validator unsignedInteger() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const bool ok = !text.empty() && text.size() <= 19 && text.find_first_not_of("0123456789") == std::string::npos;
        return ok ? std::string() : fmt::format("must be an integer in [0, 10^19) (got '{}')", text);
      },
      "UINT");
}

CLI::Option* addProtocolOption(CLI::App& sub, core::Protocol& protocol) {
  // A string checked against the names, then converted, as --shape: the help reads the names.
  return sub
      .add_option_function<std::string>(
          "--protocol",
          [&protocol](const std::string& s) {
            protocol = s == "quasi-static" ? core::Protocol::QuasiStatic : core::Protocol::Dynamic;
          },
          "dynamic: time steps until equilibrium; quasi-static: time steps until the fall is over, then "
          "contact problems solved from rest until equilibrium (nscd; Bullet stays dynamic)")
      ->check(CLI::IsMember({"dynamic", "quasi-static"}))
      ->default_str(core::toString(protocol));
}

void addRunConfigOptions(CLI::App& sub, core::RunConfig& cfg, CommonOptions& opts, bool outRequired) {
  // A string checked against the names, then converted: the help then reads {sphere,pinacoid}.
  sub.add_option_function<std::string>(
         "--shape", [&cfg](const std::string& s) { cfg.population.shape = core::shapeFromString(s); }, "Grain shape")
      ->check(CLI::IsMember({"sphere", "pinacoid"}))
      ->default_str(std::string(core::toString(cfg.population.shape)));
  sub.add_option("--length-x", cfg.box.lengthX, "Period L_x along x [d_L]")
      ->check(positiveNumber())
      ->capture_default_str();
  sub.add_option("--width", cfg.box.width, "Gap W between the side walls, or period along y with --periodic-y [d_L]")
      ->check(positiveNumber())
      ->capture_default_str();
  sub.add_flag("--periodic-y", cfg.box.periodicY, "Periodic along y instead of side walls (unconfined reference)");
  sub.add_option("--height", cfg.box.height, "Target final packing height h [d_L]")
      ->check(positiveNumber())
      ->capture_default_str();
  sub.add_option("--small-fraction", cfg.population.smallFraction,
                 "x_S, volume percentage of small grains (d_S = d_L/2)")
      ->check(realIn(0.0, 100.0, false, false, "a percentage in [0, 100]", "PERCENT"))
      ->capture_default_str();
  sub.add_option("--wall-friction", cfg.walls.friction, "Coulomb friction mu_w of the side walls (floor frictionless)")
      ->check(nonNegativeNumber())
      ->capture_default_str();
  std::vector<std::string> names;
  for (auto n : backends::backendNames()) names.emplace_back(n);
  sub.add_option("--backend", cfg.backend, "Contact backend")->check(CLI::IsMember(names))->capture_default_str();
  sub.add_option("--seed", cfg.seed, "Seed of every random stream (a run is a function of it)")
      ->check(unsignedInteger())
      ->capture_default_str();
  auto* out = sub.add_option("--out", opts.out, "Output directory (created; written all or nothing)")->type_name("DIR");
  if (outRequired) out->required();
  sub.add_option("--max-grains", cfg.deposition.maxGrains,
                 "Refuse a deposit of more grains than this (a guard against a mistyped box)")
      ->check(unsignedInteger())
      ->capture_default_str();
  sub.add_option("--grain-cap", cfg.deposition.grainCap,
                 "Shorten the box along x (length_x) so that it holds about this many grains, if it would hold "
                 "more; 0 = no cap")
      ->check(unsignedInteger())
      ->capture_default_str();
  sub.add_option("--threads", cfg.threads, "Worker threads")
      ->type_name("N")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  auto* quiet = sub.add_flag("-q,--quiet", opts.quiet, "No progress output");
  sub.add_flag("-v,--verbose", opts.verbosity, "More detail on stderr (repeatable)")->excludes(quiet);
  sub.add_option("--pinacoid-G", cfg.population.pinacoid.widthRatio, "Pinacoid width G / L")
      ->check(positiveNumber())
      ->capture_default_str();
  sub.add_option("--pinacoid-E", cfg.population.pinacoid.heightRatio, "Pinacoid height E / L")
      ->check(positiveNumber())
      ->capture_default_str();
  sub.add_option("--pinacoid-alpha", cfg.population.pinacoid.alphaDeg,
                 "Inclination of the pinacoid's triangular faces [degrees], in (0, 90)")
      ->check(realIn(0.0, 90.0, true, true, "an angle in (0, 90) degrees", "DEGREES"))
      ->capture_default_str();
}

std::string oneLineFailure(const CLI::App* app, const std::exception& e) {
  while (app != nullptr && app->get_parent() != nullptr) app = app->get_parent();
  std::string program = app != nullptr && !app->get_name().empty() ? app->get_name() : "confpack";
  // The subcommand the failure belongs to, as every other error line of it names it ("confpack
  // run: error: ..."): the one the parser had reached, if any.
  if (app != nullptr && !app->get_subcommands().empty()) program += " " + app->get_subcommands().front()->get_name();
  std::string what = e.what();
  // CLI11 messages can carry a trailing newline; keep the promise of one line.
  for (char& c : what)
    if (c == '\n') c = ' ';
  while (!what.empty() && what.back() == ' ') what.pop_back();
  return fmt::format("{}: error: {} (see --help)\n", program, what);
}

namespace {
/// The running program's name, for error lines (set by parseAndRun).
std::string& programName() {
  static std::string name = "confpack";
  return name;
}

// What the out-of-memory line names: the subcommand that checkInput or runWork last started (a
// literal) and the innermost WorkStep of the thread.
std::string_view currentCommand;
thread_local const char* currentStep = "reading the command line";

// Address space set aside at start and given back when an allocation first fails, just before
// std::bad_alloc is thrown. The unwinding that follows allocates: nlohmann::json's destructor
// keeps the children of the value it destroys on a stack, a vector as long as its largest array
// (1 MB for the packing of a 68,000-grain deposit). 16 MB covers the destruction of arrays of a
// million elements; untouched, it costs no physical memory.
constexpr std::size_t kUnwindingReserve = std::size_t{16} << 20;
std::atomic<void*> unwindingReserve{nullptr};

// Set when an allocation has failed: a std::terminate that follows with no exception current (a
// noexcept function that a bad_alloc left, as libstdc++'s directory_iterator::operator++) is that
// failure.
std::atomic<bool> allocationFailed{false};

void releaseReserveAndFail() {
  allocationFailed = true;
  std::free(unwindingReserve.exchange(nullptr));
  throw std::bad_alloc();
}

// The staged output being written, for the terminate handler (one per process at a time).
std::atomic<StagedOutput*> openOutput{nullptr};
// The last staging folder made and the user's folder it stands for: an error message names the
// user's folder, not the internal one (a write that failed in it, a disk full).
std::string stagingName, stagingTarget;
// Set once a command's output is in place: what fails after it (its summary line) fails nothing,
// and says so in this line.
std::atomic<bool> outputCommitted{false};
constexpr const char* kAfterCommit = "warning: out of memory after the output was in place (it is complete)";

/// "<program> <command>: out of memory while <step>" (or, given `instead`, that text after the
/// colon), assembled on the stack and written with one write(2): nothing here allocates, so it
/// works when memory has run out.
void writeOutOfMemoryLine(const char* instead = nullptr) noexcept {
  char line[512];
  std::size_t n = 0;
  auto put = [&](std::string_view s) {
    const std::size_t k = std::min(s.size(), sizeof line - 1 - n);  // room kept for the newline
    std::memcpy(line + n, s.data(), k);
    n += k;
  };
  put(programName());
  if (!currentCommand.empty()) {
    put(" ");
    put(currentCommand);
  }
  if (instead != nullptr) {
    put(": ");
    put(instead);
  } else {
    put(": out of memory while ");
    put(currentStep);
  }
  line[n++] = '\n';
  std::fflush(stdout);
  (void)!::write(STDERR_FILENO, line, n);
}

// An allocation that fails where no exception may leave (a noexcept destructor: nlohmann::json's
// allocates its stack) ends in std::terminate with std::bad_alloc current. Out of memory is still
// one line and exit 1 with nothing left behind: the staged output is removed here, and the
// process ends without unwinding further. Any other reason to terminate aborts as before.
[[noreturn]] void terminateOutOfMemory() noexcept {
  bool outOfMemory = false;
  if (const std::exception_ptr e = std::current_exception(); !e) {
    outOfMemory = allocationFailed.load();
  } else {
    try {
      std::rethrow_exception(e);
    } catch (const std::bad_alloc&) {
      outOfMemory = true;
    } catch (...) {
    }
  }
  if (!outOfMemory) std::abort();
  std::free(unwindingReserve.exchange(nullptr));
  if (outputCommitted.load()) {
    writeOutOfMemoryLine(kAfterCommit);
    std::_Exit(kExitOk);
  }
  if (StagedOutput* out = openOutput.exchange(nullptr)) out->discardStaging();
  writeOutOfMemoryLine();
  std::_Exit(kExitRuntimeFailure);
}

[[noreturn]] void failWith(std::string_view command, const std::exception& e, int code) {
  std::string what = e.what();
  if (!stagingName.empty())
    for (std::size_t at = what.find(stagingName); at != std::string::npos; at = what.find(stagingName, at))
      what.replace(at, stagingName.size(), stagingTarget);
  for (char& c : what)
    if (c == '\n') c = ' ';
  const std::string label = command.empty() ? programName() : programName() + " " + std::string(command);
  std::fprintf(stderr, "%s: error: %s\n", label.c_str(), what.c_str());
  throw CLI::RuntimeError(code);
}
}  // namespace

int parseAndRun(CLI::App& app, int argc, char** argv) {
  programName() = app.get_name();
  core::installStopHandlers();
  if (unwindingReserve.load() == nullptr) {
    unwindingReserve = std::malloc(kUnwindingReserve);
    std::set_new_handler(releaseReserveAndFail);
    std::set_terminate(terminateOutOfMemory);
  }
  // Out of memory is a failure of the work wherever it happens (exit 1), never bad input. By the
  // time this handler runs, the unwinding has released what the failed work held; the line is
  // still written without allocating, in case that was not enough.
  try {
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      const int code = app.exit(e);  // help -> 0; RuntimeError -> its code, silently
      if (code == kExitOk || e.get_name() == "RuntimeError") return code;
      return kExitBadInput;
    }
  } catch (const std::bad_alloc&) {
    writeOutOfMemoryLine();
    return kExitRuntimeFailure;
  }
  return kExitOk;
}

WorkStep::WorkStep(const char* what) noexcept : previous_(currentStep), uncaught_(std::uncaught_exceptions()) {
  currentStep = what;
}

void WorkStep::next(const char* what) noexcept {
  currentStep = what;
}

WorkStep::~WorkStep() {
  if (std::uncaught_exceptions() == uncaught_) currentStep = previous_;
}

namespace {

// Runs one stage of a subcommand: CLI11's own errors and out-of-memory go up to main (which
// reports them), a stop by signal exits 128 + the signal (as a shell reports a process the signal
// killed), any other error exits `failure`. Staged output has been removed on the way here
// (StagedOutput's destructor); a sweep keeps its finished runs.
void runStage(std::string_view command, const char* stepName, int failure, const std::function<void()>& body) {
  currentCommand = command;
  const WorkStep step(stepName);
  try {
    body();
  } catch (const CLI::RuntimeError&) {
    throw;
  } catch (const std::bad_alloc&) {
    if (!outputCommitted.load()) throw;
    writeOutOfMemoryLine(kAfterCommit);
  } catch (const core::Interrupted& e) {
    failWith(command, e, 128 + e.signal());
  } catch (const std::exception& e) {
    failWith(command, e, failure);
  }
}

}  // namespace

// A check can be long work (analyze analyses the packing before it writes anything): a stop there
// is no refusal of the input, and nothing is written yet.
void checkInput(std::string_view command, const std::function<void()>& checks) {
  runStage(command, "checking the input", kExitBadInput, checks);
}

void runWork(std::string_view command, const std::function<void()>& work) {
  runStage(command, "preparing the output", kExitRuntimeFailure, work);
}

CLI::Option* addAllowImplausibleFlag(CLI::App& sub, bool& allow) {
  return sub.add_flag("--allow-implausible", allow,
                      "Take a packing file that is not plausible anyway: a grain larger than the box, a solid "
                      "fraction above 1, an overlap deeper than 0.05 of the smaller grain's size, a contact point "
                      "more than 0.1 d beyond its grain (refused by default: such a file is a mistake, and its "
                      "numbers would look like results)");
}

namespace {
// A new --out, or one to be replaced (its output is staged beside it, in its parent), is refused
// before any work when its nearest existing parent is not a folder a folder can be made in (a
// read-only mount, /proc, a file): a probe folder made there and removed at once, since
// permissions alone do not tell (root may write everywhere but /proc). `verb`: "create" or
// "replace", for the message.
void checkCanCreateIn(const fs::path& target, std::string_view verb) {
  std::error_code ec;
  fs::path parent = target.parent_path();
  while (!parent.empty() && !fs::exists(parent, ec) && parent != parent.parent_path()) parent = parent.parent_path();
  if (!fs::is_directory(parent, ec))
    throw std::invalid_argument(
        fmt::format("--out: '{}' is not a folder, so '{}' cannot be made in it", parent.string(), target.string()));
  const fs::path probe = parent / fmt::format(".confpack-probe-{}", ::getpid());
  if (!fs::create_directory(probe, ec) && ec)
    throw std::invalid_argument(fmt::format("--out: cannot {} '{}': {}", verb, target.string(), ec.message()));
  fs::remove(probe, ec);
}
}  // namespace

void checkOutputTarget(const fs::path& out) {
  std::error_code ec;
  if (out.empty()) throw std::invalid_argument("--out: an output directory is required");
  const fs::path absolute = fs::absolute(out, ec).lexically_normal();
  if (!ec && absolute == absolute.root_path())
    throw std::invalid_argument(
        fmt::format("--out: '{}' is the file system's root; give a new or empty folder", out.string()));
  const fs::file_status status = fs::status(out, ec);
  if (!fs::exists(status)) {
    checkCanCreateIn(absolute, "create");
    return;
  }
  if (!fs::is_directory(status))
    throw std::invalid_argument(fmt::format("--out: '{}' exists and is not a directory", out.string()));
  if (!fs::exists(out / kOutputMarker, ec)) {
    fs::directory_iterator entries(out, ec);
    if (ec) throw std::invalid_argument(fmt::format("--out: cannot read folder '{}': {}", out.string(), ec.message()));
    if (entries != fs::directory_iterator())
      throw std::invalid_argument(
          fmt::format("--out: '{}' is a folder with files confpack did not write (it has no {}); give a new or "
                      "empty folder, or the output folder of an earlier confpack command",
                      out.string(), kOutputMarker));
  }
  checkCanCreateIn(absolute, "replace");
}

namespace {
void writeOutputMarker(const fs::path& dir) {
  // What the marker says to a user who finds it; its presence is what counts.
  core::writeFileAtomically(dir / kOutputMarker,
                            "Written by confpack: this folder is a confpack output, which the next confpack command "
                            "given it as --out may replace.\n");
}
}  // namespace

void markOutputFolder(const fs::path& dir) {
  fs::create_directories(dir);
  if (!fs::exists(dir / kOutputMarker)) writeOutputMarker(dir);
}

void applyThreads(int threads) {
#ifdef _OPENMP
  omp_set_num_threads(threads);
#else
  (void)threads;
#endif
}

namespace {
/// Absolute, normalised, without a trailing separator ("out/run/" and "out/run/." name "out/run").
fs::path normalisedTarget(const fs::path& p) {
  fs::path t = fs::absolute(p).lexically_normal();
  while (!t.has_filename() && t.has_parent_path() && t != t.parent_path()) t = t.parent_path();
  return t;
}

/// Removes the staging folders of `target` (".NAME.partial-PID") whose process is gone: a
/// command killed with SIGKILL (or by a power cut) could not remove its own.
// readdir rather than std::filesystem::directory_iterator: libstdc++ builds each entry's path
// inside a noexcept function, so an allocation failing there ends in std::terminate instead of
// the out-of-memory line.
void removeStaleStaging(const fs::path& target) {
  const std::string prefix = "." + target.filename().string() + ".partial-";
  const std::unique_ptr<DIR, int (*)(DIR*)> dir(::opendir(target.parent_path().c_str()), ::closedir);
  if (!dir) return;
  std::error_code ec;
  while (const dirent* entry = ::readdir(dir.get())) {
    const std::string_view name = entry->d_name;
    if (!name.starts_with(prefix)) continue;
    const std::string_view digits = name.substr(prefix.size());
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string_view::npos)
      continue;
    const pid_t pid = static_cast<pid_t>(std::stol(std::string(digits)));
    if (pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH) fs::remove_all(target.parent_path() / name, ec);
  }
}
}  // namespace

StagedOutput::StagedOutput(const fs::path& target, RenameFn rename, RemoveFn removeAll)
    : target_(normalisedTarget(target)),
      rename_(rename ? std::move(rename) : [](const fs::path& from, const fs::path& to) { fs::rename(from, to); }),
      removeAll_(removeAll ? std::move(removeAll) : [](const fs::path& p) { fs::remove_all(p); }) {
  // Parents that do not exist yet are ours: remember them so a failure removes them too.
  for (fs::path p = target_.parent_path(); !p.empty() && !fs::exists(p); p = p.parent_path()) {
    createdParents_.push_back(p);
    if (p == p.parent_path()) break;
  }
  staging_ = target_.parent_path() / fmt::format(".{}.partial-{}", target_.filename().string(), ::getpid());
  // The user's path in the message, not the internal staging folder that failed.
  try {
    fs::create_directories(target_.parent_path());
    removeStaleStaging(target_);
    fs::remove_all(staging_);
    fs::create_directory(staging_);
    stagingName = staging_.string();
    stagingTarget = target_.string();
    writeOutputMarker(staging_);
    openOutput.store(this);
  } catch (const fs::filesystem_error& e) {
    discardStaging();
    throw std::runtime_error(fmt::format("cannot create output folder {}: {}", target.string(), e.code().message()));
  } catch (const std::runtime_error& e) {
    discardStaging();
    throw std::runtime_error(fmt::format("cannot create output folder {}: {}", target.string(), e.what()));
  } catch (...) {  // out of memory: no destructor will remove what was made
    discardStaging();
    throw;
  }
}

void StagedOutput::discardStaging() noexcept {
  try {
    std::error_code ec;
    fs::remove_all(staging_, ec);
    for (const fs::path& p : createdParents_) fs::remove(p, ec);  // only if empty
  } catch (...) {
  }
}

StagedOutput::~StagedOutput() {
  StagedOutput* self = this;
  openOutput.compare_exchange_strong(self, nullptr);
  if (committed_ || keepStaging_) return;
  // remove_all allocates (directory entries) and may throw std::bad_alloc even with an error_code;
  // out of a destructor that would terminate the program (SIGABRT) in the middle of the unwinding
  // of an out-of-memory failure (discardStaging swallows it). The work's memory is released by
  // then (it lives in scopes inside this one), so the removal normally succeeds; if it cannot, the
  // next command on this target removes the folder (removeStaleStaging).
  discardStaging();
}

void StagedOutput::commit() {
  StagedOutput* self = this;
  openOutput.compare_exchange_strong(self, nullptr);  // from here on, its files are the output
  if (!fs::exists(target_)) {
    rename_(staging_, target_);
    committed_ = true;
    outputCommitted = true;
    return;
  }
  // Into an existing target, entry by entry. Each old entry is moved aside into the staging
  // directory before the new one takes its name (a directory, vtk/, cannot be renamed over a
  // non-empty one anyway), so that a failure midway can undo every move made so far.
  const fs::path aside = staging_ / ".replaced";
  fs::create_directory(aside);
  std::vector<fs::path> names;
  for (const auto& entry : fs::directory_iterator(staging_))
    if (entry.path() != aside) names.push_back(entry.path().filename());
  struct Move {
    fs::path name;
    bool replaced;  ///< an old entry of that name was moved aside
    bool placed;    ///< the new entry is in the target
  };
  std::vector<Move> moves;
  try {
    for (const fs::path& name : names) {
      Move& m = moves.emplace_back(Move{name, false, false});
      if (fs::exists(fs::symlink_status(target_ / name))) {
        rename_(target_ / name, aside / name);
        m.replaced = true;
      }
      rename_(staging_ / name, target_ / name);
      m.placed = true;
    }
  } catch (const std::exception& e) {
    // Undo, last move first: the new entry back into staging, the old one back in place.
    bool restored = true;
    for (auto m = moves.rbegin(); m != moves.rend(); ++m) {
      try {
        if (m->placed) rename_(target_ / m->name, staging_ / m->name);
        if (m->replaced) rename_(aside / m->name, target_ / m->name);
      } catch (const std::exception&) {
        restored = false;
      }
    }
    keepStaging_ = !restored;
    throw std::runtime_error(
        restored ? fmt::format("moving the output into {} failed, its old files are back in place: {}",
                               target_.string(), e.what())
                 : fmt::format("moving the output into {} failed and could not be undone; the old files that "
                               "were replaced are in {}: {}",
                               target_.string(), aside.string(), e.what()));
  }
  // Every new entry is in place: the command has done its work, whatever happens to the old
  // files now. One that cannot be removed (an immutable file) is left where it is and named.
  committed_ = true;
  outputCommitted = true;
  try {
    removeAll_(aside);
    fs::remove(staging_);
  } catch (const std::exception& e) {
    const auto* fsError = dynamic_cast<const fs::filesystem_error*>(&e);
    const std::string label =
        currentCommand.empty() ? programName() : programName() + " " + std::string(currentCommand);
    warning_ = fmt::format(
        "{}: warning: the output is in place in {}, but the old files it replaced could not be removed ({}); they are "
        "left in {}",
        label, target_.string(), fsError ? fsError->code().message() : std::string(e.what()), aside.string());
    std::fprintf(stderr, "%s\n", warning_.c_str());
  }
}

void writeJson(const fs::path& path, const nlohmann::json& j) {
  core::writeFileAtomically(path, j.dump(2) + "\n");
}

}  // namespace confpack::app
