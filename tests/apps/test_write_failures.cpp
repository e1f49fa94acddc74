// Write failures at every file a command writes: the test build confpack-allocation-fault
// (tests/support/allocation_fault.hpp) fails its k-th file write with ENOSPC (a full disk) or EIO
// (an I/O error), for k = 1, 2, ... until the command writes fewer files than k. Each failure must
// be exit 1 with one line naming the file's reason, and leave nothing in --out or beside it.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/fault_session.hpp"

using confpack::testing::CommandResult;
using confpack::testing::lineCount;
namespace fs = std::filesystem;

namespace {

struct WriteSession : confpack::testing::FaultSession {
  using FaultSession::FaultSession;

  /// `command --out out` with its k-th write failing with `error` (ENOSPC or EIO), for every k up
  /// to the number of files it writes; returns that number.
  int sweep(const std::string& command, const std::string& out, const std::string& error,
            const std::string& reason) const {
    for (int k = 1; k <= 200; ++k) {
      const CommandResult r =
          runFaulty("CONFPACK_FAIL_WRITE=" + std::to_string(k) + " CONFPACK_FAIL_WRITE_ERRNO=" + error,
                    command + " --out " + out);
      CAPTURE(command, k, r.code, r.err);
      if (r.code == 0) {
        CHECK(fs::exists(dir / out / ".confpack-output"));
        fs::remove_all(dir / out);
        return k - 1;
      }
      REQUIRE(r.code == 1);
      CHECK(lineCount(r.err) == 1);
      CHECK(r.err.find("write failed (" + reason + ")") != std::string::npos);
      CHECK(r.err.find(".partial-") == std::string::npos);  // the user's names, not the staging
      CHECK(!fs::exists(dir / out));
      for (const auto& e : fs::directory_iterator(dir))
        CHECK(e.path().filename().string().find(".partial-") == std::string::npos);
    }
    FAIL("still failing after 200 writes");
    return 0;
  }
};

}  // namespace

TEST_CASE("write failures: every file of run, analyze and report, on a full disk and on an I/O error",
          "[apps][cli][io]") {
  const WriteSession s("write_failures");
  const std::string run = "run --length-x 4 --width 4 --height 5 --time-limit 3 --frame-interval 500 -q";
  CHECK(s.sweep(run, "out", "ENOSPC", "No space left on device") >= 8);
  CHECK(s.sweep(run + " --backend bullet", "out", "EIO", "Input/output error") >= 8);
  REQUIRE(s.run(std::string("'") + CONFPACK_BINARY + "' " + run + " --out pile").code == 0);
  CHECK(s.sweep("analyze pile/packing.json -q", "analysis", "EIO", "Input/output error") >= 3);
  {
    std::ofstream(s.dir / "study.json")
        << R"({"format": "confpack-sweep", "version": 1, "base": {"box": {"length_x": 4, "height": 5},)"
        << R"( "compaction": {"time_limit": 2}}, "vary": {"width": [4], "backend": ["nscd", "bullet"]}})";
  }
  REQUIRE(s.run(std::string("'") + CONFPACK_BINARY + "' sweep study.json --out study -q").code == 0);
  CHECK(s.sweep("report study --no-figures", "report", "ENOSPC", "No space left on device") >= 3);
}
