// Allocation failures across whole commands, as SQLite tests them: the test build
// confpack-allocation-fault (tests/support/allocation_fault.hpp) fails its k-th allocation, for k
// spread evenly over every allocation a command makes (counted first, twice, so the points are
// the same every time). Each command must then either succeed with its whole output, or exit 1 with one
// line naming what ran out and leave nothing in --out or beside it; never crash.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/fault_session.hpp"

using confpack::testing::CommandResult;
using confpack::testing::lineCount;
namespace fs = std::filesystem;

namespace {

struct AllocationSession : confpack::testing::FaultSession {
  using FaultSession::FaultSession;

  CommandResult failingAt(long k, const std::string& args) const {
    return runFaulty("CONFPACK_FAIL_ALLOCATION=" + std::to_string(k), args);
  }
  /// The allocations `args` makes when none fails.
  long allocations(const std::string& args) const {
    const fs::path file = dir.string() + ".count";
    const CommandResult r = runFaulty("CONFPACK_COUNT_ALLOCATIONS='" + file.string() + "'", args);
    REQUIRE(r.code == 0);
    long n = 0;
    std::ifstream(file) >> n;
    fs::remove(file);
    return n;
  }
  /// `command --out out` (out a new folder of the session), its k-th allocation failing, at
  /// `points` values of k spread over the whole command; returns how many of them failed.
  int sweep(const std::string& command, const std::string& out, int points) const {
    const long n = allocations(command + " --out " + out + "-count");
    INFO(command << ": " << n << " allocations");
    REQUIRE(n > points);
    fs::remove_all(dir / (out + "-count"));
    // The points are the same every time only if the command's allocations are: count again.
    REQUIRE(allocations(command + " --out " + out + "-count") == n);
    fs::remove_all(dir / (out + "-count"));
    int failed = 0;
    for (int i = 0; i < points; ++i) {
      const long k = 1 + static_cast<long>(i) * (n - 1) / (points - 1);
      const CommandResult r = failingAt(k, command + " --out " + out);
      CAPTURE(k, r.code, r.err);
      REQUIRE((r.code == 0 || r.code == 1));
      if (r.code == 0) {
        CHECK(fs::exists(dir / out / ".confpack-output"));
      } else {
        ++failed;
        CHECK(lineCount(r.err) == 1);
        CHECK(r.err.find(": out of memory while ") != std::string::npos);
        CHECK(!fs::exists(dir / out));
      }
      for (const auto& e : fs::directory_iterator(dir))
        CHECK(e.path().filename().string().find(".partial-") == std::string::npos);
      fs::remove_all(dir / out);
    }
    return failed;
  }
};

const std::string kSpheres = "run --length-x 4 --width 4 --height 5 -q";

}  // namespace

TEST_CASE("allocation failures: run with nscd (quasi-static, spheres) fails cleanly or succeeds",
          "[apps][cli][memory]") {
  const AllocationSession s("allocation_sweep_nscd");
  CHECK(s.sweep(kSpheres + " --time-limit 3 --protocol quasi-static", "out", 40) > 0);
}

TEST_CASE("allocation failures: run with Bullet fails cleanly or succeeds", "[apps][cli][memory]") {
  const AllocationSession s("allocation_sweep_bullet");
  CHECK(s.sweep(kSpheres + " --time-limit 3 --backend bullet", "out", 40) > 0);
}

TEST_CASE("allocation failures: run with nscd on pinacoids fails cleanly or succeeds", "[apps][cli][memory]") {
  const AllocationSession s("allocation_sweep_pinacoids");
  CHECK(s.sweep("run --shape pinacoid --length-x 4 --width 4 --height 4 --time-limit 5 -q", "out", 40) > 0);
}

TEST_CASE("allocation failures: analyze and report fail cleanly or succeed", "[apps][cli][memory]") {
  const AllocationSession s("allocation_sweep_analysis");
  REQUIRE(s.failingAt(0, kSpheres + " --time-limit 4 --out pile").code == 0);
  CHECK(s.sweep("analyze pile/packing.json -q", "analysis", 40) > 0);
  {
    std::ofstream(s.dir / "study.json")
        << R"({"format": "confpack-sweep", "version": 1, "base": {"box": {"length_x": 4, "height": 5},)"
        << R"( "compaction": {"time_limit": 2}}, "vary": {"width": [4], "backend": ["nscd", "bullet"]}})";
  }
  REQUIRE(s.failingAt(0, "sweep study.json --out study -q").code == 0);
  CHECK(s.sweep("report study --no-figures", "report", 40) > 0);
}
