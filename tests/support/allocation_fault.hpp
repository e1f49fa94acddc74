#pragma once
// Out of memory at a chosen allocation, for the command line's test build (tests/CMakeLists.txt,
// confpack-allocation-fault: apps/main.cpp compiled with CONFPACK_ALLOCATION_FAULT and linked with
// allocation_fault.cpp, whose replaced operator new counts). Once armed, the k-th operator new of
// any thread, counted from the arming, fails as a real one does: the new handler is called (the
// command line's releases its reserve and throws std::bad_alloc), else std::bad_alloc is thrown.
// Every other allocation succeeds. With CONFPACK_COUNT_ALLOCATIONS=FILE it writes, at exit, the
// number of allocations made since the arming to FILE, so that a test can spread its failure
// points over a whole command (tests/apps/test_allocation_sweep.cpp). With CONFPACK_FAIL_WRITE=k
// the k-th file it writes (core::writeFileAtomically) fails with ENOSPC, or with EIO when
// CONFPACK_FAIL_WRITE_ERRNO=EIO (tests/apps/test_write_failures.cpp).

namespace confpack::testing {

/// Reads k from the environment variable CONFPACK_FAIL_ALLOCATION (unset or 0: nothing fails),
/// CONFPACK_COUNT_ALLOCATIONS and CONFPACK_FAIL_WRITE (see above).
void armAllocationFault();

}  // namespace confpack::testing
