#pragma once
// Out of memory at a chosen allocation, for the command line's test build (tests/CMakeLists.txt,
// confpack-allocation-fault: apps/main.cpp compiled with CONFPACK_ALLOCATION_FAULT and linked with
// allocation_fault.cpp, whose replaced operator new counts). Once armed, the k-th operator new of
// any thread, counted from the arming, fails as a real one does: the new handler is called (the
// command line's releases its reserve and throws std::bad_alloc), else std::bad_alloc is thrown.
// Every other allocation succeeds. tests/apps/test_main.cpp fails the command line's setup. Run
// over k for a whole command (a shell loop over CONFPACK_FAIL_ALLOCATION), some k still end in
// std::terminate: the allocation that fails is then made inside nlohmann::json's destructor
// (noexcept; it keeps the children of the value it destroys on a vector), so a sweep over a fixed
// sample of k cannot stand as a regression test yet.

namespace confpack::testing {

/// Reads k from the environment variable CONFPACK_FAIL_ALLOCATION (unset or 0: nothing fails).
void armAllocationFault();

}  // namespace confpack::testing
