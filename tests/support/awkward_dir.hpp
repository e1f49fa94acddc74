#pragma once
// Test helper: a fresh folder whose name has spaces, single and double quotes and shell
// metacharacters, for code that must pass paths to other programs without a shell.
#include <unistd.h>

#include <filesystem>
#include <string>

namespace confpack::testing {

inline std::filesystem::path awkwardDir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("confpack test " + name + " it's \"quoted\" $HOME; `x` & " + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace confpack::testing
