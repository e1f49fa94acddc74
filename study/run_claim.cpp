#include "study/run_claim.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "study/slurm.hpp"
#include "study/sweep.hpp"

namespace confpack::study {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// A break lock older than this was left by a process that died between taking and removing it
// (microseconds apart): it is removed, so that a run can never stay blocked.
constexpr std::chrono::seconds kStaleBreakLock{60};

// Field 22 of /proc/PID/stat, the process's start time in clock ticks since boot; 0 when unknown.
// The fields after the command name are counted from its closing parenthesis, since the name may
// hold spaces and parentheses.
unsigned long long processStartTicks(long pid) {
  std::ifstream in(fmt::format("/proc/{}/stat", pid));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 1));
  std::string field;
  for (int i = 3; i <= 22; ++i)
    if (!(fields >> field)) return 0;
  return std::strtoull(field.c_str(), nullptr, 10);
}

std::string slurmJobOfThisProcess() {
  const char* array = std::getenv("SLURM_ARRAY_JOB_ID");
  const char* task = std::getenv("SLURM_ARRAY_TASK_ID");
  if (array && task && *array && *task) return fmt::format("{}_{}", array, task);
  const char* job = std::getenv("SLURM_JOB_ID");
  return job ? job : "";
}

std::string freshToken() {
  static std::atomic<unsigned> counter{0};
  std::random_device rd;
  return fmt::format("{:08x}{:08x}-{}", rd(), rd(), counter++);
}

std::optional<ClaimHolder> readHolder(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return std::nullopt;
  try {
    return claimHolderFromJson(json::parse(in), file.string());
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

bool olderThan(const fs::path& file, std::chrono::seconds age) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) return false;
  return std::time(nullptr) - st.st_mtime > age.count();
}

}  // namespace

json toJson(const ClaimHolder& h) {
  return {{"host", h.host}, {"pid", h.pid},     {"start_ticks", h.startTicks},
          {"job", h.job},   {"token", h.token}, {"since", h.since}};
}

ClaimHolder claimHolderFromJson(const json& j, std::string_view source) {
  if (!j.is_object() || !j.contains("host") || !j.contains("pid") || !j.contains("token") ||
      !j.at("host").is_string() || !j.at("pid").is_number_integer() || !j.at("token").is_string())
    throw std::invalid_argument(fmt::format("{}: not a run claim (host, pid, token)", source));
  ClaimHolder h;
  h.host = j.at("host").get<std::string>();
  h.pid = j.at("pid").get<long>();
  h.startTicks = j.value("start_ticks", 0ULL);
  h.job = j.value("job", std::string());
  h.token = j.at("token").get<std::string>();
  h.since = j.value("since", std::string());
  return h;
}

ClaimHolder currentProcess() {
  ClaimHolder h;
  h.host = hostName();
  h.pid = static_cast<long>(::getpid());
  h.startTicks = processStartTicks(h.pid);
  h.job = slurmJobOfThisProcess();
  h.token = freshToken();
  h.since = utcTimestamp();
  return h;
}

std::string describe(const ClaimHolder& h) {
  std::string s = fmt::format("{} pid {}", h.host, h.pid);
  if (!h.job.empty()) s += fmt::format(" (job {})", h.job);
  return s;
}

Liveness holderLiveness(const ClaimHolder& h) {
  if (h.host == hostName()) {
    if (::kill(static_cast<pid_t>(h.pid), 0) != 0 && errno == ESRCH) return Liveness::Dead;
    // The pid runs: the same process unless it started at another time (a reused pid).
    const unsigned long long ticks = processStartTicks(h.pid);
    if (h.startTicks != 0 && ticks != 0 && ticks != h.startTicks) return Liveness::Dead;
    return Liveness::Alive;
  }
  if (h.job.empty()) return Liveness::Unknown;
  const std::optional<std::string> state = slurmJobState(h.job);
  if (!state) return Liveness::Unknown;
  return isLiveJobState(*state) ? Liveness::Alive : Liveness::Dead;
}

std::optional<RunClaim> RunClaim::acquire(const fs::path& claimsDir, const std::string& name, ClaimHolder* heldBy,
                                          const LivenessFn& alive) {
  fs::create_directories(claimsDir);
  const fs::path file = claimsDir / name;
  const fs::path breakLock = claimsDir / ("." + name + ".break");
  ClaimHolder me = currentProcess();
  const fs::path mine = privateFileName(claimsDir, name);
  {
    std::ofstream out(mine);
    out << toJson(me).dump();
    if (!out.flush()) throw std::runtime_error(fmt::format("{}: cannot write", mine.string()));
  }
  struct RemoveMine {
    const fs::path& path;
    ~RemoveMine() { ::unlink(path.c_str()); }
  } removeMine{mine};

  // A few rounds: a claim released or broken between our link and our read is simply tried again.
  for (int round = 0; round < 8; ++round) {
    if (::link(mine.c_str(), file.c_str()) == 0) return RunClaim(file, std::move(me));
    if (errno != EEXIST)
      throw std::runtime_error(fmt::format("{}: cannot take the claim ({})", file.string(), std::strerror(errno)));
    const std::optional<ClaimHolder> holder = readHolder(file);
    if (!holder) continue;  // released meanwhile (a claim file always holds a whole claim: it is linked complete)
    if (alive(*holder) != Liveness::Dead) {
      if (heldBy) *heldBy = *holder;
      return std::nullopt;
    }
    // A dead holder: break its claim, one breaker at a time. Inside the break lock the claim file
    // cannot change under us: a dead holder removes nothing, and nobody can link a claim over an
    // existing one, so the token read here is still the file's when we remove it.
    if (::link(mine.c_str(), breakLock.c_str()) != 0) {
      if (errno == EEXIST && olderThan(breakLock, kStaleBreakLock)) {
        ::unlink(breakLock.c_str());
        continue;
      }
      if (heldBy) *heldBy = *holder;  // another process is breaking it, and will take the run
      return std::nullopt;
    }
    const std::optional<ClaimHolder> still = readHolder(file);
    if (still && still->token == holder->token) ::unlink(file.c_str());
    ::unlink(breakLock.c_str());
  }
  throw std::runtime_error(fmt::format("{}: the claim keeps changing hands; try again", file.string()));
}

RunClaim::RunClaim(RunClaim&& other) noexcept : file_(std::move(other.file_)), holder_(std::move(other.holder_)) {
  other.file_.clear();
}

RunClaim& RunClaim::operator=(RunClaim&& other) noexcept {
  if (this != &other) {
    release();
    file_ = std::move(other.file_);
    holder_ = std::move(other.holder_);
    other.file_.clear();
  }
  return *this;
}

RunClaim::~RunClaim() {
  release();
}

void RunClaim::release() noexcept {
  if (file_.empty()) return;
  const std::optional<ClaimHolder> now = readHolder(file_);
  if (now && now->token == holder_.token) ::unlink(file_.c_str());
  file_.clear();
}

std::optional<ClaimHolder> readClaim(const fs::path& claimsDir, const std::string& name) {
  return readHolder(claimsDir / name);
}

}  // namespace confpack::study
