#pragma once
// Claims on the runs of a sweep folder, so that two processes handed the same run (a job array
// submitted again while a task of the earlier one still runs, two tasks on different nodes of a
// cluster sharing the folder) never work in its folder at once.
//
// A claim is the file SWEEPDIR/claims/rNNNN, holding who took it (host, pid, Slurm job). It is
// taken with link(2) of a complete private file onto that name: link fails with EEXIST when the
// name exists, so exactly one of any number of contenders wins, also on NFS, where link is atomic
// on the server (O_EXCL was not before NFSv3). Its holder removes it when the run has its marker
// or was interrupted. A claim whose holder is dead (killed with SIGKILL, a node lost, a job past
// its time limit) is broken by the next contender, under a second link-taken file so that only one
// process breaks it.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/packing_io.hpp"

namespace confpack::study {

using core::hostName;
using core::privateFileName;

/// Who holds a claim: enough to tell from any node whether it is still alive.
struct ClaimHolder {
  std::string host;  ///< gethostname() of the holder
  long pid = 0;      ///< its process id on that host
  unsigned long long startTicks =
      0;              ///< its start time (/proc/PID/stat, clock ticks since boot): a reused pid differs; 0 = unknown
  std::string job;    ///< its Slurm job: "ARRAYJOB_TASK" in an array, "JOBID" otherwise; empty outside Slurm
  std::string token;  ///< unique per claim taken: a holder removes only its own
  std::string since;  ///< when the claim was taken (UTC, ISO 8601)
};

nlohmann::json toJson(const ClaimHolder& h);
/// Throws std::invalid_argument naming `source` when `j` is not a claim.
ClaimHolder claimHolderFromJson(const nlohmann::json& j, std::string_view source);

/// This process as a holder (host, pid, start time, Slurm job from SLURM_ARRAY_JOB_ID and
/// SLURM_ARRAY_TASK_ID or SLURM_JOB_ID), with a fresh token.
ClaimHolder currentProcess();

/// "vm pid 4711 (job 12_3)": a holder as a user reads it.
std::string describe(const ClaimHolder& h);

enum class Liveness { Alive, Dead, Unknown };
using LivenessFn = std::function<Liveness(const ClaimHolder&)>;

/// The default test: a holder on this host is alive while its pid runs the process that took the
/// claim; one on another host is alive while Slurm lists its job in a live state (squeue); Unknown
/// when neither can be told (another host without a job, or squeue not answering). An Unknown
/// holder is treated as alive: a claim is never broken on a guess.
Liveness holderLiveness(const ClaimHolder& h);

/// A claim held by this process; the destructor gives it up (release()).
class RunClaim {
 public:
  /// Tries to claim run `name` in `claimsDir` (created when missing). Returns the claim, or
  /// nothing when another holder has it and `alive` does not say Dead; `heldBy` then receives that
  /// holder. A Dead holder's claim is broken and taken over.
  static std::optional<RunClaim> acquire(const std::filesystem::path& claimsDir, const std::string& name,
                                         ClaimHolder* heldBy = nullptr, const LivenessFn& alive = holderLiveness);

  RunClaim(RunClaim&& other) noexcept;
  RunClaim& operator=(RunClaim&& other) noexcept;
  RunClaim(const RunClaim&) = delete;
  RunClaim& operator=(const RunClaim&) = delete;
  ~RunClaim();

  /// Removes the claim file if it is still this claim's (never another holder's).
  void release() noexcept;
  const ClaimHolder& holder() const { return holder_; }

 private:
  RunClaim(std::filesystem::path file, ClaimHolder holder) : file_(std::move(file)), holder_(std::move(holder)) {}
  std::filesystem::path file_;
  ClaimHolder holder_;
};

/// The holder of run `name`'s claim, nothing when it is not claimed (or the claim file cannot be
/// read as one: it is then left to acquire() to judge).
std::optional<ClaimHolder> readClaim(const std::filesystem::path& claimsDir, const std::string& name);

/// The folder of a sweep's claims.
inline std::filesystem::path claimsDir(const std::filesystem::path& sweepDir) {
  return sweepDir / "claims";
}

}  // namespace confpack::study
