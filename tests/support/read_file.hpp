#pragma once
// Test helper: a whole file as a string ("" when it cannot be read; the caller's checks fail then).
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace confpack::testing {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace confpack::testing
