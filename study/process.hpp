#pragma once
// Running an external program (gnuplot for the report's figures) without a shell: the arguments
// go to the program as they are, so a path with spaces or quotes needs no quoting, and nothing in
// them is ever interpreted.
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace confpack::study {

struct ProcessOptions {
  std::filesystem::path workDir;         ///< the child's working directory; empty = ours
  std::filesystem::path output;          ///< file that receives stdout and stderr; empty = /dev/null
  std::chrono::milliseconds timeout{0};  ///< killed (SIGKILL) after this long; 0 = no limit
};

struct ProcessResult {
  bool started = false;
  int exitCode = -1;  ///< when it exited
  int signal = 0;     ///< when a signal ended it
  bool timedOut = false;
  std::string error;  ///< why it did not start
  bool ok() const { return started && !timedOut && signal == 0 && exitCode == 0; }
  /// "exited with status 3", "killed by signal 9", "timed out after 2 s (killed)", "could not start: ..."
  std::string describe(std::chrono::milliseconds timeout) const;
};

/// Runs argv[0] (searched in PATH when it has no '/') with argv[1..], stdin from /dev/null, and
/// waits for it. A stop request (SIGINT or SIGTERM, core/interrupt.hpp) while it runs kills it
/// (SIGKILL) and throws core::Interrupted: a program that hangs cannot hold a command past Ctrl-C
/// or a cluster's time limit.
ProcessResult runProcess(const std::vector<std::string>& argv, const ProcessOptions& options = {});

/// The last non-empty line of a program's output file (ProcessOptions::output), without its end of
/// line: what a failing program said last. Empty when the file is missing or blank.
std::string lastOutputLine(const std::filesystem::path& output);

}  // namespace confpack::study
