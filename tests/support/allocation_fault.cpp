#include "tests/support/allocation_fault.hpp"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>

#include "core/packing_io.hpp"

namespace {
// Allocations to go until the one that fails (that one takes it from 1 to 0); <= 0: disarmed.
std::atomic<long> countdown{0};
// Every operator new since the start, for CONFPACK_COUNT_ALLOCATIONS.
std::atomic<long> made{0};
const char* countFile = nullptr;

// Writes to go until the one that fails, and the errno it fails with (CONFPACK_FAIL_WRITE).
std::atomic<long> writesLeft{0};
int writeErrno = ENOSPC;

int failKthWrite(const std::filesystem::path&) {
  return writesLeft.fetch_sub(1) == 1 ? writeErrno : 0;
}

void writeCount() {
  if (std::FILE* f = std::fopen(countFile, "w")) {
    std::fprintf(f, "%ld\n", made.load());
    std::fclose(f);
  }
}
}  // namespace

// The replaceable global allocation functions ([new.delete.single]): the array forms call these.
void* operator new(std::size_t size) {
  made.fetch_add(1, std::memory_order_relaxed);
  if (countdown.load(std::memory_order_relaxed) > 0 && countdown.fetch_sub(1) == 1) {
    // As a real failure: the new handler, which throws or returns to have the allocation retried.
    const std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
  for (;;) {
    if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
    const std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
// Every other form that allocates with malloc or frees with free is replaced too, so that a
// pointer never goes from a replaced form to a library's own (AddressSanitizer's, under
// .ci/sanitize, reports that as an alloc-dealloc mismatch): the nothrow forms (the standard
// library's temporary buffers) and the array forms. The aligned forms are left to the library,
// which then both allocates and frees.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return ::operator new(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size) {
  return ::operator new(size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return ::operator new(size, std::nothrow);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}

namespace confpack::testing {

void armAllocationFault() {
  if (const char* k = std::getenv("CONFPACK_FAIL_WRITE")) {
    writesLeft = std::strtol(k, nullptr, 10);
    if (const char* e = std::getenv("CONFPACK_FAIL_WRITE_ERRNO"); e != nullptr && std::strcmp(e, "EIO") == 0)
      writeErrno = EIO;
    if (writesLeft > 0) confpack::core::setWriteFault(failKthWrite);
  }
  if (const char* k = std::getenv("CONFPACK_FAIL_ALLOCATION")) countdown = std::strtol(k, nullptr, 10);
  if ((countFile = std::getenv("CONFPACK_COUNT_ALLOCATIONS")) != nullptr) {
    made = 0;
    std::atexit(writeCount);
  }
}

}  // namespace confpack::testing
