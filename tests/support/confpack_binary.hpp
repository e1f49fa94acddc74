#pragma once
// Runs a real binary (`confpack`, CONFPACK_BINARY, or `confpack-bench`, CONFPACK_BENCH_BINARY, set
// by tests/CMakeLists.txt) as a user runs it, in a scratch folder of its own, with its exit code
// and its stdout and stderr.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "tests/support/read_file.hpp"
#include "tests/support/scratch.hpp"

namespace confpack::testing {

struct CommandResult {
  int code = -1;  ///< exit code, -1 if confpack did not exit normally
  std::string out, err;
};

/// A scratch folder (see scratch.hpp) removed at the end, in which `program` runs.
struct ConfpackSession {
  std::filesystem::path dir;
  std::string program;

  explicit ConfpackSession(const std::string& name, std::string program = CONFPACK_BINARY)
      : dir(freshDir(name)), program(std::move(program)) {}
  ~ConfpackSession() { std::filesystem::remove_all(dir); }
  ConfpackSession(const ConfpackSession&) = delete;
  ConfpackSession& operator=(const ConfpackSession&) = delete;

  /// Runs `program <args>` inside the folder. stdout and stderr are captured beside it, not in
  /// it, so that the folder shows only what confpack wrote.
  CommandResult run(const std::string& args) const {
    const std::filesystem::path outFile = dir.string() + ".stdout", errFile = dir.string() + ".stderr";
    const std::string cmd = "cd '" + dir.string() + "' && '" + program + "' " + args + " > '" + outFile.string() +
                            "' 2> '" + errFile.string() + "'";
    const int status = std::system(cmd.c_str());
    CommandResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(outFile);
    r.err = slurp(errFile);
    std::filesystem::remove(outFile);
    std::filesystem::remove(errFile);
    return r;
  }

  /// Names of the folder's entries (to check what was, or was not, written).
  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(dir)) out.push_back(e.path().filename().string());
    return out;
  }
  bool empty() const { return std::filesystem::is_empty(dir); }
};

/// Starts CONFPACK_BINARY with `args` in `dir` as a child process, stdout to /dev/null and stderr
/// to `errFile` (nowhere if empty), under an address-space limit of `limitMiB` (RLIMIT_AS; 0 = none),
/// and returns its PID at once, for a test that signals or waits for it; -1 if fork failed.
inline pid_t startConfpack(const std::filesystem::path& dir, std::vector<std::string> args,
                           const std::filesystem::path& errFile = {}, std::size_t limitMiB = 0) {
  const pid_t pid = fork();
  if (pid != 0) return pid;
  if (::chdir(dir.c_str()) != 0) _exit(127);
  const int null = ::open("/dev/null", O_WRONLY);
  const int err = errFile.empty() ? null : ::open(errFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ::dup2(null, 1);
  ::dup2(err, 2);
  if (limitMiB > 0) {
    const rlimit limit{limitMiB << 20, limitMiB << 20};
    if (::setrlimit(RLIMIT_AS, &limit) != 0) _exit(126);
  }
  std::vector<char*> argv{const_cast<char*>(CONFPACK_BINARY)};
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(CONFPACK_BINARY, argv.data());
  _exit(127);
}

/// How a confpack started with startConfpack ended after a signal: its wait status and what it
/// wrote to its error file.
struct Stopped {
  int status = 0;
  std::string message;
};

/// Sends `signal` to `pid` after `delay`, waits for it and reads (then removes) `errFile`.
inline Stopped stopAfter(pid_t pid, std::chrono::milliseconds delay, int signal, const std::filesystem::path& errFile) {
  std::this_thread::sleep_for(delay);
  ::kill(pid, signal);
  Stopped out;
  ::waitpid(pid, &out.status, 0);
  out.message = slurp(errFile);
  std::filesystem::remove(errFile);
  return out;
}

/// Number of lines (newline characters) of a captured output.
inline int lineCount(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

}  // namespace confpack::testing
