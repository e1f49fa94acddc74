// What the subcommands share (apps/cli_common.hpp): an output directory that appears complete or
// not at all (StagedOutput), --out checks, and JSON written atomically.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/cli_common.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/scratch.hpp"

namespace fs = std::filesystem;
using confpack::app::StagedOutput;
using confpack::testing::slurp;

namespace {

/// Names of the entries of a directory, sorted.
std::vector<std::string> entriesOf(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

TEST_CASE("a staged output never committed leaves nothing behind, not even the parents it made") {
  const fs::path root = confpack::testing::freshDir("cli_common_unwound");
  try {
    StagedOutput out(root / "new" / "deeper" / "run");
    REQUIRE(fs::is_directory(out.dir()));
    CHECK(out.dir().parent_path() == root / "new" / "deeper");
    std::ofstream(out.dir() / "result.json") << "{}";
    throw std::runtime_error("the work failed");
  } catch (const std::runtime_error&) {
  }
  CHECK(fs::is_empty(root));  // no target, no staging folder, no parents
  fs::remove_all(root);
}

TEST_CASE("a staged output removes the staging folders of dead processes and leaves live ones") {
  const fs::path root = confpack::testing::freshDir("cli_common_stale");
  const pid_t dead = fork();  // a process that has exited and been reaped: its PID is free
  REQUIRE(dead >= 0);
  if (dead == 0) _exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string stale = ".run.partial-" + std::to_string(dead);
  const std::string live = ".run.partial-" + std::to_string(::getppid());  // our parent is alive
  fs::create_directories(root / stale / "vtk");
  fs::create_directories(root / live);
  fs::create_directories(root / ".other.partial-1");  // another target's: not ours to judge
  {
    StagedOutput out(root / "run");
    out.commit();
  }
  CHECK_FALSE(fs::exists(root / stale));
  CHECK(fs::exists(root / live));
  CHECK(fs::exists(root / ".other.partial-1"));
  fs::remove_all(root);
}

TEST_CASE("a committed staged output appears whole, or replaces the entries it staged") {
  const fs::path root = confpack::testing::freshDir("cli_common_commit");
  {
    StagedOutput out(root / "run");
    std::ofstream(out.dir() / "a.txt") << "first a";
    fs::create_directory(out.dir() / "vtk");
    std::ofstream(out.dir() / "vtk" / "old.vtu") << "old frame";
    CHECK_FALSE(fs::exists(root / "run"));  // nothing visible before the commit
    out.commit();
  }
  CHECK(entriesOf(root) == std::vector<std::string>{"run"});
  CHECK(slurp(root / "run" / "a.txt") == "first a");
  // Over an existing target: staged entries replace theirs (a staged folder replaces the old one
  // as a whole), entries not staged stay.
  std::ofstream(root / "run" / "keep.txt") << "kept";
  {
    StagedOutput out(root / "run");
    std::ofstream(out.dir() / "a.txt") << "second a";
    fs::create_directory(out.dir() / "vtk");
    std::ofstream(out.dir() / "vtk" / "new.vtu") << "new frame";
    out.commit();
  }
  CHECK(entriesOf(root) == std::vector<std::string>{"run"});
  CHECK(entriesOf(root / "run") == std::vector<std::string>{"a.txt", "keep.txt", "vtk"});
  CHECK(slurp(root / "run" / "a.txt") == "second a");
  CHECK(slurp(root / "run" / "keep.txt") == "kept");
  CHECK(entriesOf(root / "run" / "vtk") == std::vector<std::string>{"new.vtu"});
  fs::remove_all(root);
}

TEST_CASE("an --out that is an existing file is refused, and JSON is written whole and reads back equal") {
  const fs::path root = confpack::testing::freshDir("cli_common_out");
  std::ofstream(root / "file") << "keep";
  CHECK_THROWS(confpack::app::checkOutputTarget(root / "file"));
  CHECK_NOTHROW(confpack::app::checkOutputTarget(root / "absent"));
  CHECK_NOTHROW(confpack::app::checkOutputTarget(root));
  const nlohmann::json j = {{"phi", 0.1 + 0.2}, {"name", "r0001"}, {"list", {1, 2, 3}}};
  confpack::app::writeJson(root / "r.json", j);
  CHECK(nlohmann::json::parse(slurp(root / "r.json")) == j);
  CHECK(slurp(root / "r.json").back() == '\n');
  CHECK(entriesOf(root) == std::vector<std::string>{"file", "r.json"});
  fs::remove_all(root);
}
