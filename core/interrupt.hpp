#pragma once
// Ctrl-C (SIGINT) and SIGTERM (what a cluster sends a job at its time limit) as a request to stop
// at the next safe point: the signal handler only records the signal; long loops (a compaction's
// steps, a sweep's runs, the analysis's slices, cells and pairs) poll stopSignal() and throw
// Interrupted, so that staged output is removed on the way out and the command can say where it
// stopped (exit 128 + the signal: 130 or 143).
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

/// A safe point of a long loop: throws Interrupted when SIGINT or SIGTERM asked to stop. `where()`
/// is called only then, so that a loop does not format its position on every pass.
template <class Where>
void stopIfRequested(Where&& where) {
  if (const int signal = stopSignal(); signal != 0) throw Interrupted(signal, where());
}

}  // namespace confpack::core
