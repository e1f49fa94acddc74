// The command line's entry point (apps/main.cpp) when memory runs out, anywhere: in its setup or in
// the work of a command. The test build confpack-allocation-fault fails the k-th allocation
// (tests/support/allocation_fault.hpp): whatever k, a command exits 0 with its output, or exit 1
// with one line saying it ran out of memory and nothing left in --out.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/support/confpack_binary.hpp"

namespace fs = std::filesystem;
using confpack::testing::CommandResult;
using confpack::testing::ConfpackSession;
using confpack::testing::lineCount;

namespace {

/// A session whose program is env(1), which sets the variable for the test build (runFailingAt).
struct FaultSession : ConfpackSession {
  explicit FaultSession(const std::string& name) : ConfpackSession(name, "/usr/bin/env") {}
};

/// `confpack-allocation-fault <args>` in `s` with its k-th allocation failing (0: none).
CommandResult runFailingAt(const ConfpackSession& s, long k, const std::string& args) {
  return s.run("CONFPACK_FAIL_ALLOCATION=" + std::to_string(k) + " '" + CONFPACK_ALLOCATION_FAULT_BINARY + "' " + args);
}

/// Every entry of the session's folder but `keep`: what a failed command left behind.
std::vector<std::string> leftBehind(const ConfpackSession& s, const std::vector<std::string>& keep) {
  std::vector<std::string> out;
  for (const std::string& name : s.entries())
    if (std::find(keep.begin(), keep.end(), name) == keep.end()) out.push_back(name);
  return out;
}

/// Runs `args` (writing --out out) with the failure at a sample of allocations, from the first to
/// past the last a successful command makes: each either succeeds or fails with the one line.
void sweepAllocationFailures(const ConfpackSession& s, const std::string& args, const std::string& subcommand,
                             const std::vector<std::string>& inputs) {
  int succeeded = 0, failed = 0;
  // About 1.5x apart: some 35 points up to 3e6 allocations.
  for (double k = 1.0; k < 3e6 && succeeded < 2; k = std::ceil(k * 1.5)) {
    const long at = static_cast<long>(k);
    CAPTURE(at);
    const CommandResult r = runFailingAt(s, at, args + " --out out");
    INFO("stderr: " << r.err);
    if (r.code == 0) {
      ++succeeded;
      CHECK((fs::exists(s.dir / "out" / "result.json") || fs::exists(s.dir / "out" / "packing.json")));
      fs::remove_all(s.dir / "out");
    } else {
      ++failed;
      CHECK(r.code == 1);
      CHECK(lineCount(r.err) == 1);
      CHECK_THAT(r.err, Catch::StartsWith("confpack " + subcommand + ": out of memory while ") ||
                            Catch::StartsWith("confpack: out of memory while "));
    }
    CHECK(leftBehind(s, inputs).empty());  // neither out/ nor its staging folder
  }
  // The sample reached both sides: failures early, success once k passed the last allocation.
  CHECK(failed > 0);
  CHECK(succeeded > 0);
}

}  // namespace

TEST_CASE("an allocation that fails while the command line is set up is one line and exit 1", "[apps][cli]") {
  // Issue 62, failure 4: std::terminate with two lines on stderr (before parseAndRun's catch).
  const FaultSession s("main_setup_out_of_memory");
  for (long k : {1L, 2L, 10L}) {
    CAPTURE(k);
    const CommandResult r = runFailingAt(s, k, "deposit --help");
    CHECK(r.code == 1);
    CHECK(r.err == "confpack: out of memory while setting up the command line\n");
  }
  // Not armed, the same binary is confpack.
  CHECK(runFailingAt(s, 0, "deposit --help").code == 0);
}

// Hidden ([.]: not run by ctest), run by hand with `test_apps "[allocation-sweep]"`. It fails today:
// with the k-th allocation failing, some k end in std::terminate (exit 134, two lines) because the
// allocation that fails is made inside a noexcept function of a library: nlohmann::json's
// destructor (it keeps the children of the value it destroys on a vector), in the normal flow as
// well as while unwinding. About 1 in 60 of the allocations of a small analyze were such points,
// most while the results are written; a fixed sample of k would pass or not depending on where the scratch folder's path
// moves the count, so the sample cannot stand as a regression test until those are dealt with.
TEST_CASE("an allocation failing anywhere in run or analyze: success, or exit 1 with one line and no output",
          "[.][allocation-sweep]") {
  const FaultSession s("main_allocation_sweep");
  REQUIRE(runFailingAt(s, 0, "deposit --length-x 3 --width 3 --height 2 --out dep -q").code == 0);
  sweepAllocationFailures(s, "run --length-x 3 --width 3 --height 2 --time-limit 2 -q", "run", {"dep"});
  sweepAllocationFailures(s, "analyze dep/packing.json -q", "analyze", {"dep"});
}
