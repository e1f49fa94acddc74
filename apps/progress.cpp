#include "apps/progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace confpack::app {

Progress::Progress(std::string label, bool enabled, double plainInterval_s)
    : label_(std::move(label)),
      enabled_(enabled),
      live_(enabled && ::isatty(STDERR_FILENO) == 1),
      plainInterval_(plainInterval_s),
      start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() {
  // Never leave the cursor at the end of a half-written live line (an exception unwinding).
  if (lineOpen_) std::fputs("\n", stderr);
}

double Progress::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::update(double fraction, std::string_view status) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  const double t = elapsed();
  const double pct = 100.0 * std::clamp(fraction, 0.0, 1.0);
  if (live_) {
    if (t - lastPrint_ < 0.1) return;
    // \r returns to the start of the line, ESC[K clears what a longer previous line left.
    fmt::print(stderr, "\r\033[K{}: {:5.1f}% {} [{:.1f} s]", label_, pct, status, t);
    std::fflush(stderr);
    lineOpen_ = true;
  } else {
    if (t - lastPrint_ < plainInterval_) return;
    fmt::print(stderr, "{}: {:.1f}% {} [{:.1f} s]\n", label_, pct, status, t);
  }
  lastPrint_ = t;
}

void Progress::done(std::string_view status) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  if (live_) fmt::print(stderr, "\r\033[K");
  fmt::print(stderr, "{}: done {} [{:.1f} s]\n", label_, status, elapsed());
  lineOpen_ = false;
}

void Progress::note(std::string_view line) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  if (lineOpen_) fmt::print(stderr, "\r\033[K");
  fmt::print(stderr, "{}: {}\n", label_, line);
  lineOpen_ = false;
  lastPrint_ = -1e300;  // the stretch that follows reports at once
}

}  // namespace confpack::app
