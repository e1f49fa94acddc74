// `confpack reproduce` and `confpack sweep` with the real binary and real physics: a sweep killed
// with SIGKILL and resumed, and the tiny scale end to end. The study definitions (the
// library's reproductionSweep) are tested in tests/study/test_reproduce.cpp.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "study/sweep.hpp"
#include "tests/support/read_file.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using nlohmann::json;

namespace {

using confpack::testing::slurp;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("confpack_test_repro_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

int runConfpack(const fs::path& dir, const std::string& args) {
  const std::string cmd = "cd '" + dir.string() + "' && '" + CONFPACK_BINARY + "' " + args + " > out.txt 2> err.txt";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST_CASE("a sweep killed with SIGKILL and restarted finishes with no run lost or redone") {
  const fs::path dir = scratch("kill");
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

  REQUIRE(runConfpack(dir, "sweep s.json --out sw") == 0);
  const std::string out = slurp(dir / "out.txt");
  CHECK(out.find(std::to_string(markers.size()) + " earlier") != std::string::npos);
  for (const char* r : {"r0000", "r0001", "r0002", "r0003"}) {
    INFO(r);
    CHECK(study::runStatus(dir / "sw" / "runs" / r) == study::RunStatus::Done);
    CHECK(fs::exists(dir / "sw" / "runs" / r / "result.json"));
  }
  for (const auto& [name, text] : markers) CHECK(slurp(dir / "sw" / "runs" / name / study::kDoneMarker) == text);
  // Both backends of a pile read the same deposit file.
  CHECK(fs::exists(dir / "sw" / "deposits" / "d0000.json"));
  CHECK(fs::exists(dir / "sw" / "deposits" / "d0001.json"));
  fs::remove_all(dir);
}

TEST_CASE("reproduce --scale tiny: the whole chain to a report") {
  const fs::path dir = scratch("tiny");
  const auto t0 = std::chrono::steady_clock::now();
  const int code = runConfpack(dir, "reproduce --scale tiny --out tiny --jobs 2");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO("stderr: " << slurp(dir / "err.txt"));
  REQUIRE(code == 0);
  WARN("reproduce --scale tiny took " << seconds << " s");
  const std::string md = slurp(dir / "tiny" / "report" / "report.md");
  const std::string html = slurp(dir / "tiny" / "report" / "report.html");
  CHECK(md.find("# confpack study report: tiny") != std::string::npos);
  CHECK(md.find("| r0005 |") != std::string::npos);
  CHECK(md.find("### solid_fraction") != std::string::npos);
  CHECK(md.find("nscd − bullet") != std::string::npos);
  CHECK(html.find("</html>") != std::string::npos);
  for (int i = 0; i < 6; ++i) {
    char name[8];
    std::snprintf(name, sizeof name, "r%04d", i);
    CHECK(study::runStatus(dir / "tiny" / "runs" / name) == study::RunStatus::Done);
  }
  // Running it again finds everything done and only rewrites the report.
  REQUIRE(runConfpack(dir, "reproduce --scale tiny --out tiny") == 0);
  CHECK(slurp(dir / "out.txt").find("0 finished now, 6 earlier") != std::string::npos);
  fs::remove_all(dir);
}
