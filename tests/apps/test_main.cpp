// The command line's entry point (apps/main.cpp) when memory runs out in its setup, before
// parseAndRun: the test build confpack-allocation-fault fails the k-th allocation
// (tests/support/allocation_fault.hpp).
#include <catch2/catch.hpp>
#include <string>

#include "tests/support/fault_session.hpp"

using confpack::testing::CommandResult;
using confpack::testing::FaultSession;

namespace {

/// `confpack-allocation-fault <args>` in `s` with its k-th allocation failing (0: none).
CommandResult runFailingAt(const FaultSession& s, long k, const std::string& args) {
  return s.runFaulty("CONFPACK_FAIL_ALLOCATION=" + std::to_string(k), args);
}

}  // namespace

TEST_CASE("an allocation that fails while the command line is set up is one line and exit 1", "[apps][cli]") {
  // The failure this guards against: std::terminate with two lines on stderr (before parseAndRun's catch).
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
