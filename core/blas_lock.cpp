#include "core/blas_lock.hpp"

std::unique_lock<std::mutex> confpack::core::blasLock() {
  static std::mutex m;
  return std::unique_lock<std::mutex>(m);
}
