#pragma once
// An exception must not leave an OpenMP parallel region: the runtime then calls std::terminate,
// an abort without a message that leaves the staging folder behind. The work of each thread runs
// through ParallelFailure::capture(), which keeps the first exception any thread throws (an
// out-of-memory std::bad_alloc of a contact list growing, say); after the region, rethrow() throws
// it on the calling thread, which unwinds as from serial code ("out of memory while ...", exit 1).
// The path without an exception costs nothing: no lock, no allocation, the same work in the same
// order.
#include <atomic>
#include <exception>

namespace confpack::core {

class ParallelFailure {
 public:
  /// Runs fn() and keeps the exception it throws, if it is the first one of the region.
  template <class Fn>
  void capture(Fn&& fn) noexcept {
    try {
      fn();
    } catch (...) {
      // std::current_exception() refers to the exception in flight: it allocates nothing.
      if (!failed_.exchange(true)) first_ = std::current_exception();
    }
  }
  /// Whether a thread has failed: after a barrier, the work that needs the others' results skips.
  bool failed() const noexcept { return failed_.load(); }
  /// After the region: throws the first exception kept, if any.
  void rethrow() const {
    if (first_) std::rethrow_exception(first_);
  }

 private:
  std::atomic<bool> failed_{false};
  std::exception_ptr first_;  ///< written by the first thread that failed, read after the region
};

}  // namespace confpack::core
