#pragma once
// The quasi-static finisher of a compaction (docs/model.md, "Protocols").
//
// Static equilibrium of frictionless rigid grains under gravity is the first-order optimality
// condition of  min U(q) = -F_ext.q  subject to non-penetration, the contact forces being the
// multipliers (Roux, PRE 61, 6802, 2000). The finisher approaches it by a sequence of steps from
// rest, each the implicit Euler (Moreau-Jean, theta = 1) step of length h:
//     min_dq  1/2 dq.M dq / h^2 - F_ext.dq   subject to  gap_c + J_c dq >= 0  (and Coulomb at walls),
// with contacts re-detected before each step (core::ContactBackend::quasiStaticStep). That is a proximal
// point iteration on U with the metric M / h^2: a sequential quadratic program in the spirit of
// the sequential linear programming of Torquato & Jiao (PRE 82, 061302, 2010) and Donev's LP
// jamming, for rigid grains with the dynamics' own contact solver. At a fixed point dq = 0, so
// F_ext + J^T lambda = 0 with lambda >= 0 on closed contacts: static equilibrium.
//
// Step length: h starts at the dynamic step and doubles after every step, up to finisher_max_step
// (a long step is what makes the iteration converge in few steps). The trust radius (a fraction of
// the smallest grain) caps the motion of each grain's surface in one step, so that the linearised
// gaps stay accurate and no contact can cross the alert band unseen.
#include "core/backend.hpp"
#include "core/run_config.hpp"

namespace confpack::compaction {

class QuasiStaticFinisher {
 public:
  /// `smallestSize` scales the trust radius and the settle tolerance; `firstStep` is the first h [t0].
  QuasiStaticFinisher(const core::CompactionDef& def, double smallestSize, double firstStep);

  /// One finisher step on `backend` (which must have hasQuasiStaticStep()).
  core::QuasiStaticMove step(core::ContactBackend& backend);

  /// The last step moved no grain's surface more than the settle tolerance.
  bool settled() const { return steps_ > 0 && lastMove_.maxDisplacement <= settleTolerance_; }
  long steps() const { return steps_; }
  long clippedSteps() const { return clipped_; }
  double lastStepLength() const { return lastStep_; }  ///< h of the last step [t0]
  const core::QuasiStaticMove& lastMove() const { return lastMove_; }

  /// The finisher's counters and next step, for a run's checkpoint (docs/model.md, "Checkpoints").
  nlohmann::json saveState() const;
  /// Takes back what saveState() wrote; throws std::invalid_argument on anything else.
  void restoreState(const nlohmann::json& state);

 private:
  double trustRadius_ = 0.0;      ///< [d_L]
  double settleTolerance_ = 0.0;  ///< [d_L]
  double maxStep_ = 0.0;          ///< [t0]
  double h_ = 0.0;                ///< the next step [t0]
  double lastStep_ = 0.0;
  long steps_ = 0, clipped_ = 0;
  core::QuasiStaticMove lastMove_;
};

}  // namespace confpack::compaction
