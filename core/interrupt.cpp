#include "core/interrupt.hpp"

#include <atomic>
#include <csignal>
#include <string>

namespace confpack::core {

namespace {

// Lock-free, so the handler may store into it (async-signal-safe).
std::atomic<int> requested{0};
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void onStopSignal(int signal) {
  requested.store(signal, std::memory_order_relaxed);
}

std::string signalName(int signal) {
  if (signal == SIGINT) return "SIGINT";
  if (signal == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal);
}

}  // namespace

Interrupted::Interrupted(int signal, const std::string& where)
    : std::runtime_error("interrupted by " + signalName(signal) + (where.empty() ? "" : " " + where)),
      signal_(signal) {}

void installStopHandlers() {
  static const bool installed = [] {
    struct sigaction action {};
    action.sa_handler = onStopSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;  // blocking reads and writes carry on; the loops poll the request
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
    return true;
  }();
  (void)installed;
}

int stopSignal() {
  return requested.load(std::memory_order_relaxed);
}

}  // namespace confpack::core
