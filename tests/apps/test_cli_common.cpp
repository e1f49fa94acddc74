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
using confpack::app::checkOutputTarget;
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
  CHECK(fs::exists(root / "run" / confpack::app::kOutputMarker));  // what makes it confpack's
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
  CHECK(entriesOf(root / "run") == std::vector<std::string>{".confpack-output", "a.txt", "keep.txt", "vtk"});
  CHECK(slurp(root / "run" / "a.txt") == "second a");
  CHECK(slurp(root / "run" / "keep.txt") == "kept");
  CHECK(entriesOf(root / "run" / "vtk") == std::vector<std::string>{"new.vtu"});
  fs::remove_all(root);
}

TEST_CASE("a commit into an existing target that fails between two renames puts the old files back") {
  // Issue 23, failure 4: a failed move left old and new files mixed. The rename that fails is
  // injected, in turn at every rename a commit makes (3 old entries moved aside, 5 new ones moved
  // in, the output marker among them): whichever fails, the target holds exactly its old files afterwards, and no
  // staging folder is left.
  const fs::path root = confpack::testing::freshDir("cli_common_rollback");
  auto writeOld = [&] {
    fs::remove_all(root / "run");
    fs::create_directories(root / "run" / "vtk");
    std::ofstream(root / "run" / "a.txt") << "old a";
    std::ofstream(root / "run" / "b.txt") << "old b";
    std::ofstream(root / "run" / "keep.txt") << "kept";
    std::ofstream(root / "run" / "vtk" / "old.vtu") << "old frame";
  };
  auto checkOld = [&] {
    CHECK(entriesOf(root) == std::vector<std::string>{"run"});
    CHECK(entriesOf(root / "run") == std::vector<std::string>{"a.txt", "b.txt", "keep.txt", "vtk"});
    CHECK(slurp(root / "run" / "a.txt") == "old a");
    CHECK(slurp(root / "run" / "b.txt") == "old b");
    CHECK(slurp(root / "run" / "keep.txt") == "kept");
    CHECK(entriesOf(root / "run" / "vtk") == std::vector<std::string>{"old.vtu"});
  };
  constexpr int kRenames = 8;
  for (int failAt = 1; failAt <= kRenames; ++failAt) {
    CAPTURE(failAt);
    writeOld();
    int calls = 0;
    auto rename = [&](const fs::path& from, const fs::path& to) {
      if (++calls == failAt) throw std::runtime_error("injected rename failure");
      fs::rename(from, to);
    };
    {
      StagedOutput out(root / "run", rename);
      std::ofstream(out.dir() / "a.txt") << "new a";
      std::ofstream(out.dir() / "b.txt") << "new b";
      std::ofstream(out.dir() / "c.txt") << "new c";
      fs::create_directory(out.dir() / "vtk");
      std::ofstream(out.dir() / "vtk" / "new.vtu") << "new frame";
      CHECK_THROWS_WITH(out.commit(), Catch::Contains("its old files are back in place") &&
                                          Catch::Contains("injected rename failure"));
    }
    checkOld();
  }
  // The same commit without a failure makes exactly kRenames renames and replaces the files.
  writeOld();
  int calls = 0;
  {
    StagedOutput out(root / "run", [&](const fs::path& from, const fs::path& to) {
      ++calls;
      fs::rename(from, to);
    });
    std::ofstream(out.dir() / "a.txt") << "new a";
    std::ofstream(out.dir() / "b.txt") << "new b";
    std::ofstream(out.dir() / "c.txt") << "new c";
    fs::create_directory(out.dir() / "vtk");
    std::ofstream(out.dir() / "vtk" / "new.vtu") << "new frame";
    out.commit();
  }
  CHECK(calls == kRenames);
  CHECK(entriesOf(root) == std::vector<std::string>{"run"});
  CHECK(entriesOf(root / "run") ==
        std::vector<std::string>{".confpack-output", "a.txt", "b.txt", "c.txt", "keep.txt", "vtk"});
  CHECK(slurp(root / "run" / "a.txt") == "new a");
  CHECK(entriesOf(root / "run" / "vtk") == std::vector<std::string>{"new.vtu"});
  fs::remove_all(root);
}

TEST_CASE("an --out that is an existing file is refused, and JSON is written whole and reads back equal") {
  const fs::path root = confpack::testing::freshDir("cli_common_out");
  std::ofstream(root / "file") << "keep";
  CHECK_THROWS(confpack::app::checkOutputTarget(root / "file"));
  CHECK_NOTHROW(confpack::app::checkOutputTarget(root / "absent"));
  const nlohmann::json j = {{"phi", 0.1 + 0.2}, {"name", "r0001"}, {"list", {1, 2, 3}}};
  confpack::app::writeJson(root / "r.json", j);
  CHECK(nlohmann::json::parse(slurp(root / "r.json")) == j);
  CHECK(slurp(root / "r.json").back() == '\n');
  CHECK(entriesOf(root) == std::vector<std::string>{"file", "r.json"});
  fs::remove_all(root);
}

TEST_CASE(
    "the output rule: --out must be new, empty or confpack's own, and the root or a folder of other files are "
    "refused") {
  // The failure this guards against: `run --out /` wrote into the file system's root, and a folder of the
  // user's was filled or its entries replaced.
  using confpack::app::checkOutputTarget;
  const fs::path root = confpack::testing::freshDir("cli_common_out_rule");
  CHECK_THROWS_WITH(checkOutputTarget("/"), "--out: '/' is the file system's root; give a new or empty folder");
  fs::create_directory(root / "empty");
  CHECK_NOTHROW(checkOutputTarget(root / "empty"));
  fs::create_directory(root / "theirs");
  std::ofstream(root / "theirs" / "thesis.tex") << "years of work";
  CHECK_THROWS_WITH(checkOutputTarget(root / "theirs"),
                    "--out: '" + (root / "theirs").string() +
                        "' is a folder with files confpack did not write (it has no .confpack-output); give a new "
                        "or empty folder, or the output folder of an earlier confpack command");
  CHECK_THROWS_WITH(checkOutputTarget(root / "theirs" / "."), Catch::Contains("confpack did not write"));
  {
    StagedOutput out(root / "ours");
    std::ofstream(out.dir() / "result.json") << "{}";
    out.commit();
  }
  CHECK_NOTHROW(checkOutputTarget(root / "ours"));  // written by confpack: its marker is there
  // The marker of a sweep or study folder that confpack fills itself.
  confpack::app::markOutputFolder(root / "sweep");
  CHECK_NOTHROW(checkOutputTarget(root / "sweep"));
  CHECK(slurp(root / "theirs" / "thesis.tex") == "years of work");
  fs::remove_all(root);
}

TEST_CASE("a new --out that cannot be made is refused before any work, naming the folder and the reason") {
  // The failure this guards against: run --out /proc/x did all its work, then failed (exit 1) when it
  // created its output.
  CHECK_THROWS_WITH(checkOutputTarget("/proc/x"), Catch::StartsWith("--out: cannot create '/proc/x': "));
  CHECK_THROWS_WITH(checkOutputTarget("/proc/x/y/z"), Catch::StartsWith("--out: cannot create '/proc/x/y/z': "));
  const fs::path root = confpack::testing::freshDir("cli_common_probe");
  { std::ofstream(root / "file") << "x"; }
  CHECK_THROWS_WITH(checkOutputTarget(root / "file" / "out"), Catch::Contains("is not a folder"));
  CHECK_NOTHROW(checkOutputTarget(root / "new" / "deeper"));
  CHECK(!fs::exists(root / "new"));  // the probe leaves nothing behind
  fs::remove_all(root);
}

TEST_CASE("a staged output that cannot be created names the user's folder and the reason, not its staging path") {
  // The failure this guards against: /proc/x gave the raw error on ".x.partial-PID".
  try {
    StagedOutput out("/proc/x");
    FAIL("a staging folder was created in /proc");
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Catch::StartsWith("cannot create output folder /proc/x: "));
    CHECK(what.find("partial") == std::string::npos);
  }
}

TEST_CASE("old files that cannot be removed after a complete commit are a warning naming where they are left") {
  // The failure this guards against: an immutable file of the old output made a command whose new output was
  // all in place exit 1. The removal of the old files is injected to fail, as chattr +i makes it.
  const fs::path root = confpack::testing::freshDir("cli_common_leftover");
  fs::create_directories(root / "run" / "vtk");
  std::ofstream(root / "run" / "a.txt") << "old a";
  std::ofstream(root / "run" / "vtk" / "old.vtu") << "old frame";
  auto immutable = [](const fs::path& p) {
    throw fs::filesystem_error("cannot remove all", p, std::make_error_code(std::errc::operation_not_permitted));
  };
  std::string leftover;
  {
    StagedOutput out(root / "run", {}, immutable);
    std::ofstream(out.dir() / "a.txt") << "new a";
    fs::create_directory(out.dir() / "vtk");
    std::ofstream(out.dir() / "vtk" / "new.vtu") << "new frame";
    REQUIRE_NOTHROW(out.commit());
    leftover = (out.dir() / ".replaced").string();
    CHECK_THAT(out.warning(), Catch::Contains(": warning: the output is in place in " + (root / "run").string()) &&
                                  Catch::Contains("(Operation not permitted)") &&
                                  Catch::EndsWith("they are left in " + leftover));
  }
  CHECK(slurp(root / "run" / "a.txt") == "new a");
  CHECK(entriesOf(root / "run" / "vtk") == std::vector<std::string>{"new.vtu"});
  // The old files are where the warning says, whole.
  CHECK(slurp(fs::path(leftover) / "a.txt") == "old a");
  CHECK(slurp(fs::path(leftover) / "vtk" / "old.vtu") == "old frame");
  // Without a failure there is no warning and nothing left beside the target.
  {
    StagedOutput out(root / "run");
    std::ofstream(out.dir() / "a.txt") << "third a";
    out.commit();
    CHECK(out.warning().empty());
  }
  fs::remove_all(leftover);
  fs::remove(fs::path(leftover).parent_path());
  CHECK(entriesOf(root) == std::vector<std::string>{"run"});
  fs::remove_all(root);
}
