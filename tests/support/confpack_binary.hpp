#pragma once
// Runs a real binary (`confpack`, CONFPACK_BINARY, or `confpack-bench`, CONFPACK_BENCH_BINARY, set
// by tests/CMakeLists.txt) as a user runs it, in a scratch folder of its own, with its exit code
// and its stdout and stderr.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>
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
    const std::string cmd = "cd '" + dir.string() + "' && '" + program + "' " + args + " > '" +
                            outFile.string() + "' 2> '" + errFile.string() + "'";
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

/// Number of lines (newline characters) of a captured output.
inline int lineCount(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

}  // namespace confpack::testing
