// `confpack sweep` with the real binary and real physics: a sweep killed with SIGKILL and resumed
// loses no run and redoes none. The sweep engine's bookkeeping is tested in
// tests/study/test_sweep.cpp.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "study/sweep.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::ConfpackSession;
using confpack::testing::slurp;

TEST_CASE("a sweep killed with SIGKILL and restarted finishes with no run lost or redone") {
  const ConfpackSession s("cmd_sweep_kill");
  const fs::path& dir = s.dir;
  // Four small, short runs of real physics (the time limit, not equilibrium, ends them).
  std::ofstream(dir / "s.json") << R"({
    "name": "kill",
    "base": { "box": { "length_x": 3, "height": 3 }, "compaction": { "time_limit": 1.5 } },
    "vary": { "width": [3, 4], "seed": [1], "backend": ["nscd", "bullet"] } })";
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) _exit(127);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl(CONFPACK_BINARY, CONFPACK_BINARY, "sweep", "s.json", "--out", "sw", "--jobs", "1", (char*)nullptr);
    _exit(127);
  }
  // Kill as soon as the first run is finished (the second is then in progress or about to be).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(dir / "sw" / "runs" / "r0000" / study::kDoneMarker) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(fs::exists(dir / "sw" / "runs" / "r0000" / study::kDoneMarker));

  std::map<std::string, std::string> markers;  // finished before the kill: content must not change
  for (const auto& e : fs::directory_iterator(dir / "sw" / "runs"))
    if (fs::exists(e.path() / study::kDoneMarker))
      markers[e.path().filename().string()] = slurp(e.path() / study::kDoneMarker);
  INFO("finished before the kill: " << markers.size());
  CHECK(markers.size() < 4);

  const auto resumed = s.run("sweep s.json --out sw");
  REQUIRE(resumed.code == 0);
  CHECK(resumed.out.find(std::to_string(markers.size()) + " earlier") != std::string::npos);
  for (const char* r : {"r0000", "r0001", "r0002", "r0003"}) {
    INFO(r);
    CHECK(study::runStatus(dir / "sw" / "runs" / r) == study::RunStatus::Done);
    CHECK(fs::exists(dir / "sw" / "runs" / r / "result.json"));
  }
  for (const auto& [name, text] : markers) CHECK(slurp(dir / "sw" / "runs" / name / study::kDoneMarker) == text);
  // Both backends of a pile read the same deposit file.
  CHECK(fs::exists(dir / "sw" / "deposits" / "d0000.json"));
  CHECK(fs::exists(dir / "sw" / "deposits" / "d0001.json"));
}

TEST_CASE("confpack sweep refuses a sweep file listing more runs than --max-runs: one line, exit 2") {
  const ConfpackSession s("cmd_sweep_max_runs");
  std::ofstream(s.dir / "huge.json") << R"({"vary": {"width": [4], "replicas": 100000000}})";
  std::ofstream(s.dir / "two.json") << R"({"vary": {"width": [4, 5]}})";
  const auto huge = s.run("sweep huge.json --list");
  CHECK(huge.code == 2);
  CHECK(huge.err == "confpack sweep: error: huge.json: vary: lists 1e+08 runs, more than the limit of 100000 (check "
                    "the lists and replicas, or raise the limit with --max-runs)\n");
  const auto two = s.run("sweep two.json --list --max-runs 1");
  CHECK(two.code == 2);
  CHECK_THAT(two.err, Catch::Contains("lists 2 runs, more than the limit of 1"));
  CHECK(s.run("sweep two.json --list --max-runs 2").code == 0);
  std::vector<std::string> entries = s.entries();
  std::sort(entries.begin(), entries.end());
  CHECK(entries == std::vector<std::string>{"huge.json", "two.json"});  // nothing written
}
