#pragma once
// Progress of long work on stderr (README, "Command line"): on a terminal one live line rewritten
// in place (at most 10 times a second); otherwise (a log file, a cluster job) a plain line now and
// then, so logs stay readable. Silent when disabled (--quiet).
#include <chrono>
#include <mutex>
#include <string>
#include <string_view>

namespace confpack::app {

class Progress {
 public:
  /// `label` starts every line ("deposit"). `enabled` false makes every call a no-op.
  /// `plainInterval_s`: seconds between plain lines when stderr is not a terminal.
  Progress(std::string label, bool enabled, double plainInterval_s = 10.0);
  ~Progress();

  /// Reports `fraction` done, in [0, 1], with a short status ("1200/3000 placeholders").
  /// Safe to call from several threads.
  void update(double fraction, std::string_view status = {});
  /// Ends the live line with a final status (also printed in plain mode).
  void done(std::string_view status = {});
  /// Prints `line` as a line of its own ("label: line"), clearing the live line first; the next
  /// update() is printed at once, on a new line. For events between stretches of progress (a
  /// case begins, a compaction ends).
  void note(std::string_view line);

  /// True when stderr is a terminal (live mode).
  bool live() const { return live_; }

 private:
  double elapsed() const;
  std::string label_;
  bool enabled_;
  bool live_;
  double plainInterval_;
  std::chrono::steady_clock::time_point start_;
  double lastPrint_ = -1e300;
  bool lineOpen_ = false;
  std::mutex mutex_;
};

}  // namespace confpack::app
