#include "study/process.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <thread>

#include "core/interrupt.hpp"

extern char** environ;

namespace confpack::study {

std::string ProcessResult::describe(std::chrono::milliseconds timeout) const {
  if (!started) return "could not start: " + error;
  if (timedOut) return fmt::format("timed out after {:g} s (killed)", static_cast<double>(timeout.count()) / 1000.0);
  if (signal != 0) return fmt::format("killed by signal {}", signal);
  return fmt::format("exited with status {}", exitCode);
}

namespace {

// posix_spawn's objects, released on every path out.
struct SpawnSetup {
  posix_spawn_file_actions_t actions;
  SpawnSetup() { posix_spawn_file_actions_init(&actions); }
  ~SpawnSetup() { posix_spawn_file_actions_destroy(&actions); }
  SpawnSetup(const SpawnSetup&) = delete;
  SpawnSetup& operator=(const SpawnSetup&) = delete;
};

}  // namespace

ProcessResult runProcess(const std::vector<std::string>& argv, const ProcessOptions& options) {
  ProcessResult r;
  if (argv.empty() || argv[0].empty()) {
    r.error = "no program";
    return r;
  }
  SpawnSetup setup;
  const std::string dir = options.workDir.string();
  posix_spawn_file_actions_addopen(&setup.actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  // The output file is opened after the change of directory: a relative path is the caller's,
  // so make it absolute first.
  const std::string outAbs =
      options.output.empty() ? std::string("/dev/null") : std::filesystem::absolute(options.output).string();
  if (!dir.empty()) posix_spawn_file_actions_addchdir_np(&setup.actions, dir.c_str());
  posix_spawn_file_actions_addopen(&setup.actions, STDOUT_FILENO, outAbs.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&setup.actions, STDOUT_FILENO, STDERR_FILENO);

  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &setup.actions, nullptr, args.data(), environ);
  if (rc != 0) {
    r.error = fmt::format("{}: {}", argv[0], std::strerror(rc));
    return r;
  }
  r.started = true;

  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + options.timeout;
  auto pause = std::chrono::milliseconds(1);
  int status = 0;
  const auto killChild = [&] {
    kill(pid, SIGKILL);
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
  };
  // Polled rather than a blocking waitpid: the stop handlers restart system calls (SA_RESTART),
  // so a blocking wait would not return on Ctrl-C.
  for (;;) {
    const pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) {
      r.started = false;
      r.error = fmt::format("waitpid: {}", std::strerror(errno));
      return r;
    }
    if (const int signal = core::stopSignal(); signal != 0) {
      killChild();
      throw core::Interrupted(signal, fmt::format("while {} ran", argv[0]));
    }
    if (w == 0 && options.timeout.count() > 0 && Clock::now() >= deadline) {
      killChild();
      r.timedOut = true;
      return r;
    }
    if (w == 0) {
      std::this_thread::sleep_for(pause);
      pause = std::min(pause * 2, std::chrono::milliseconds(50));
    }
  }
  if (WIFEXITED(status)) r.exitCode = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  return r;
}

std::string lastOutputLine(const std::filesystem::path& output) {
  std::ifstream in(output);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  while (!last.empty() && (last.back() == '\r' || last.back() == ' ')) last.pop_back();
  return last;
}

}  // namespace confpack::study
