#pragma once
// Out of memory on demand, in one thread only: while a FailAllocationsOffThisThread lives, every
// operator new of any other thread throws std::bad_alloc (an OpenMP worker's contact list, say),
// while the thread that made it (Catch2's, the caller of the parallel phase) allocates as usual.
// The replaced operator new is in failing_allocation.cpp, linked into test_backends only.

namespace confpack::testing {

class FailAllocationsOffThisThread {
 public:
  FailAllocationsOffThisThread();
  ~FailAllocationsOffThisThread();
  FailAllocationsOffThisThread(const FailAllocationsOffThisThread&) = delete;
  FailAllocationsOffThisThread& operator=(const FailAllocationsOffThisThread&) = delete;
  /// Allocations refused so far.
  static int refused();
};

}  // namespace confpack::testing
