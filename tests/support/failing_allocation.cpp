#include "tests/support/failing_allocation.hpp"

#include <atomic>
#include <cstdlib>
#include <new>
#include <thread>

namespace {
std::atomic<bool> failing{false};
std::atomic<int> refusedCount{0};
std::thread::id allowed;  // written before `failing` is set, read only while it is
}  // namespace

// The replaceable global allocation functions ([new.delete.single]): the array and aligned forms
// of the standard library call these or malloc and free directly.
void* operator new(std::size_t size) {
  if (failing.load(std::memory_order_acquire) && std::this_thread::get_id() != allowed) {
    refusedCount.fetch_add(1);
    throw std::bad_alloc();
  }
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}

namespace confpack::testing {

FailAllocationsOffThisThread::FailAllocationsOffThisThread() {
  allowed = std::this_thread::get_id();
  refusedCount = 0;
  failing.store(true, std::memory_order_release);
}

FailAllocationsOffThisThread::~FailAllocationsOffThisThread() {
  failing.store(false, std::memory_order_release);
}

int FailAllocationsOffThisThread::refused() {
  return refusedCount.load();
}

}  // namespace confpack::testing
