#pragma once
// One lock for every call into BLAS and LAPACK through SuiteSparse (CHOLMOD's factorisations in
// nscd's interior-point solver, SPQR's in the rigidity analysis). Debian's serial OpenBLAS, the
// one the README installs, is not safe to call from two threads at once, and `sweep --jobs 2`
// runs two runs as two threads of one process: without the lock the finishers of two W = 10
// piles (at rest in 27 and 20 steps alone) crept for 600 steps and more side by side.
#include <mutex>

namespace confpack::core {

/// Held for the duration of one SuiteSparse call; uncontended within one run.
std::unique_lock<std::mutex> blasLock();

}  // namespace confpack::core
