// Running a program without a shell (study/process.hpp).
#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>

#include "study/process.hpp"
#include "tests/support/awkward_dir.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::awkwardDir;
using confpack::testing::slurp;

TEST_CASE("process: arguments and working directory reach the program as they are, no shell") {
  const fs::path dir = awkwardDir("process");
  const std::string arg = "it's \"quoted\" $HOME; echo no `id` > x & |";
  const fs::path out = dir / "out put.txt";
  study::ProcessResult r = study::runProcess({"printf", "%s\\n", arg}, {{}, out, {}});
  CHECK(r.ok());
  CHECK(slurp(out) == arg + "\n");
  CHECK_FALSE(fs::exists(dir / "x"));
  r = study::runProcess({"pwd"}, {dir, out, {}});
  CHECK(r.ok());
  CHECK(slurp(out) == fs::canonical(dir).string() + "\n");
  // Exit status and failure to start.
  r = study::runProcess({"sh", "-c", "echo oops >&2; exit 3"}, {{}, out, {}});
  CHECK(r.started);
  CHECK(r.exitCode == 3);
  CHECK_FALSE(r.ok());
  CHECK(slurp(out) == "oops\n");
  CHECK(r.describe({}) == "exited with status 3");
  r = study::runProcess({(dir / "no such program").string()});
  CHECK_FALSE(r.started);
  CHECK(r.describe({}).find("no such program") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("process: a program that outlives its timeout is killed") {
  const auto t0 = std::chrono::steady_clock::now();
  const study::ProcessResult r = study::runProcess({"sleep", "20"}, {{}, {}, std::chrono::milliseconds(150)});
  CHECK(r.timedOut);
  CHECK_FALSE(r.ok());
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(5));
  CHECK(r.describe(std::chrono::milliseconds(150)) == "timed out after 0.15 s (killed)");
}
