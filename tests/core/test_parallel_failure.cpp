// core::ParallelFailure (core/parallel_failure.hpp): an exception thrown in an OpenMP parallel
// region comes out after it, on the calling thread, instead of terminating the program.
#include <catch2/catch.hpp>
#include <stdexcept>
#include <string>

#include "core/parallel_failure.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace confpack;

namespace {

/// This thread's index in the team (0 without OpenMP).
int threadIndex() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

}  // namespace

TEST_CASE("ParallelFailure carries the first exception of a parallel region out of it") {
  SECTION("no exception: nothing thrown, every thread's work done") {
    core::ParallelFailure failure;
    int done[2] = {0, 0};
#pragma omp parallel num_threads(2)
    {
      const int t = threadIndex();
      failure.capture([&] { done[t] = 1; });
    }
    CHECK_NOTHROW(failure.rethrow());
    CHECK_FALSE(failure.failed());
    CHECK(done[0] == 1);
  }
  SECTION("every thread throws: one of their exceptions, with its type and message") {
    core::ParallelFailure failure;
#pragma omp parallel num_threads(2)
    {
      const int t = threadIndex();
      failure.capture([&] { throw std::out_of_range("thread " + std::to_string(t)); });
    }
    CHECK(failure.failed());
    CHECK_THROWS_AS(failure.rethrow(), std::out_of_range);
    CHECK_THROWS_WITH(failure.rethrow(), Catch::StartsWith("thread "));
  }
}
