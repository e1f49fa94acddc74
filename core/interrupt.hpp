#pragma once
// Ctrl-C (SIGINT) and SIGTERM (what a cluster sends a job at its time limit) as a request to stop
// at the next safe point: the signal handler only records the signal; long loops (a compaction's
// steps, a sweep's runs, the analysis's slices, cells and pairs) poll stopSignal() and throw
// Interrupted, so that staged output is removed on the way out and the command can say where it
// stopped (exit 128 + the signal: 130 or 143).
#include <new>
#include <stdexcept>
#include <string>

namespace confpack::core {

/// Thrown at a safe point after SIGINT or SIGTERM.
class Interrupted : public std::runtime_error {
 public:
  /// `where` says where it stopped, e.g. "at t = 3.2 (step 1400)".
  Interrupted(int signal, const std::string& where);
  int signal() const { return signal_; }

 private:
  int signal_;
};

/// Routes SIGINT and SIGTERM to the stop request (once per process; later calls do nothing).
void installStopHandlers();

/// The signal that asked to stop, or 0.
int stopSignal();

/// Records that an allocation failed and was served from a reserve set aside for that (the
/// command line's new handler): the next safe point throws std::bad_alloc. The failure is thus
/// reported from a loop, where unwinding is safe, and not from wherever the allocation was made,
/// which may be a destructor (nlohmann::json's allocates), where a throw ends the program.
void requestStopForMemory() noexcept;

/// True once requestStopForMemory was called.
bool memoryRanOut() noexcept;

/// A safe point of a long loop: throws Interrupted when SIGINT or SIGTERM asked to stop, and
/// std::bad_alloc when memory ran out (requestStopForMemory). `where()` is called only then, so
/// that a loop does not format its position on every pass.
template <class Where>
void stopIfRequested(Where&& where) {
  if (memoryRanOut()) throw std::bad_alloc();
  if (const int signal = stopSignal(); signal != 0) throw Interrupted(signal, where());
}

}  // namespace confpack::core
