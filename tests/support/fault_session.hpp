#pragma once
// A scratch session that runs the fault-injection test build confpack-allocation-fault
// (tests/support/allocation_fault.hpp, CONFPACK_ALLOCATION_FAULT_BINARY, tests/apps only) under
// env(1), which sets the variables that arm its faults.
#include <string>

#include "tests/support/confpack_binary.hpp"

namespace confpack::testing {

struct FaultSession : ConfpackSession {
  explicit FaultSession(const std::string& name) : ConfpackSession(name, "/usr/bin/env") {}

  /// `confpack-allocation-fault <args>` with the environment `variables` ("NAME=value ...").
  CommandResult runFaulty(const std::string& variables, const std::string& args) const {
    return run(variables + " '" + CONFPACK_ALLOCATION_FAULT_BINARY + "' " + args);
  }
};

}  // namespace confpack::testing
