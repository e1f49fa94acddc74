#pragma once
// Picks, call after call, the team size of one parallel phase of the nscd step (1 thread or the
// configured count) by timing both. The phases give the same bits for any team size, so the
// choice changes only the speed. With more runnable threads than cores a parallel region waits for
// a thread that is not running: 5 to 10 times the single-thread phase (a 3,655-sphere pile's broad
// phase, 2 cores, load 6 to 9: 8 s against 1.6 s over 791 steps); on free cores the team wins.
#include <algorithm>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace confpack::nscd {

/// Team-size chooser for one phase: in every epoch, the first kTrial calls run with
/// `maxThreads`, the next kTrial with 1, and the rest with whichever was faster in total. An
/// epoch lasts kEpoch calls; each epoch the team loses doubles the next one (up to kMaxEpoch),
/// so that on a machine where the team keeps losing its trials cost almost nothing.
class ThreadChoice {
 public:
  static constexpr int kTrial = 8;        ///< calls timed per candidate per epoch
  static constexpr int kEpoch = 256;      ///< calls per epoch (the trials cost <= 2 kTrial / kEpoch)
  static constexpr int kMaxEpoch = 8192;  ///< longest epoch, after repeated losses of the team

  explicit ThreadChoice(int maxThreads = 1) : max_(std::max(1, maxThreads)) {}

  /// Team size for the next call (then report its wall time with record()).
  int next() const {
    if (max_ == 1) return 1;
    if (call_ < kTrial) return max_;
    if (call_ < 2 * kTrial) return 1;
    return teamWins_ ? max_ : 1;
  }
  /// Wall time of the call just made with next()'s team [s].
  void record(double seconds) {
    if (max_ == 1) return;
    if (call_ < kTrial)
      teamTime_ += seconds;
    else if (call_ < 2 * kTrial)
      oneTime_ += seconds;
    if (++call_ == 2 * kTrial) {
      teamWins_ = teamTime_ < oneTime_;
      epoch_ = teamWins_ ? kEpoch : std::min(2 * epoch_, kMaxEpoch);
    }
    if (call_ == epoch_) {
      call_ = 0;
      teamTime_ = oneTime_ = 0.0;
    }
  }
  int maxThreads() const { return max_; }
  /// Length of the current epoch [calls].
  int epochLength() const { return epoch_; }

 private:
  int max_ = 1;
  int call_ = 0;  // position in the current epoch
  int epoch_ = kEpoch;
  double teamTime_ = 0.0, oneTime_ = 0.0;
  bool teamWins_ = true;
};

/// CHOLMOD's supernodal factorisation (SuiteSparse 5) opens OpenMP teams of a fixed 4 threads
/// for copy loops of a few hundred flops each: on 2 cores, 7.5 million futex calls in a 20 s
/// finisher, a third of its time spent in the kernel. While one lives, OpenMP may
/// give a team fewer threads than asked when the cores are busy (dynamic adjustment); those loops'
/// results do not depend on their team.
class DynamicOpenMpTeams {
 public:
#ifdef _OPENMP
  DynamicOpenMpTeams() : saved_(omp_get_dynamic()) {
    omp_set_dynamic(1);
  }
  ~DynamicOpenMpTeams() {
    omp_set_dynamic(saved_);
  }

 private:
  int saved_;
#endif
};

}  // namespace confpack::nscd
