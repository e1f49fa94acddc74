#pragma once
// Scratch folders for tests that write files: confpack_test_<name>_<pid> in the system's
// temporary folder, so parallel test processes never share one.
#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace confpack::testing {

/// The scratch path for `name`, with anything left there by an earlier run removed (not created).
inline std::filesystem::path scratchPath(const std::string& name) {
  const std::filesystem::path p =
      std::filesystem::temp_directory_path() / ("confpack_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  return p;
}

/// An empty scratch folder for `name`.
inline std::filesystem::path freshDir(const std::string& name) {
  const std::filesystem::path p = scratchPath(name);
  std::filesystem::create_directories(p);
  return p;
}

/// An empty scratch folder for `name`, removed with its contents when the test leaves its scope,
/// so that repeated runs leave nothing in the temporary folder.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name) : path_(freshDir(name)) {}
  ~ScratchDir() {
    std::error_code ignored;  // a destructor must not throw; a leftover is harmless
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace confpack::testing
