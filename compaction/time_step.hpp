#pragma once
// The time step of a compaction (docs/model.md, "Time step"): the fixed step from the deposit's
// drop, and the adaptive step that follows the grains' speeds.
#include <vector>

#include "compaction/deposition.hpp"
#include "core/backend.hpp"
#include "core/grain.hpp"
#include "core/run_config.hpp"
#include "core/types.hpp"

namespace confpack::compaction {

/// The fixed time step (docs/model.md, "Time step"): a grain should not move more than d_L/100 per
/// step with v_max = sqrt(2 g dh), dh the expected drop of the free surface:
///   dt = (1/100) sqrt(d_L / (2 dh)) sqrt(d_L / g).
/// dh = pile height - (grain volume / (L_x W phi_expected)), floored at one grain size.
double defaultTimeStep(const core::RunConfig& cfg, const Deposit& deposit);

/// Largest growth of the adaptive time step from one step to the next [-].
inline constexpr double kAdaptiveGrowth = 1.25;

/// An adaptive compaction also checks equilibrium whenever this much simulated time has passed
/// since its last check [t0]: its steps grow 50-fold and more, so that check_interval steps would
/// leave tens of t0 between checks. 0.5 t0 is about as often as the fixed step's default checks
/// (200 steps of 2.3e-3 t0 on msp-w10).
inline constexpr double kAdaptiveCheckSpacing = 0.5;

/// The step of an adaptive compaction (compaction.adaptive_dt). No grain should move more than
/// d_L/100 per step; the fixed step meets that at the worst speed of the compaction,
/// sqrt(2 g dh), which the pile reaches only while it falls. This step meets it at the speeds the
/// grains have now: the largest dt with v dt + g dt^2 / 2 <= s, where v is the fastest motion of
/// any grain's boundary (|v| + |omega| r_bound; |v| for a sphere, whose spin leaves its boundary
/// in place) and s is a hundredth of the smallest grain's size
/// (d_L/100 for a monodisperse sample; smaller grains get a proportionally smaller bound, so that
/// nscd's alert distance, a fraction of the smaller grain of a pair, still covers an approach).
/// Clamped to [floor, kAdaptiveGrowth x previous]: never below the fixed step, and growing only
/// gradually, so that a grain set moving by a contact within a step is caught a step later.
/// The grains' radii and the bound s are fixed for a compaction: they are read once, here.
class AdaptiveTimeStep {
 public:
  AdaptiveTimeStep(const std::vector<core::Grain>& grains, double gravity, double floor);
  /// The step after one of length `previous`, from the grains' states now.
  double next(double previous, const std::vector<core::BodyState>& states) const;

 private:
  std::vector<double> spinLever_;  ///< Grain::spinLever of each grain [d_L]
  double motion_ = 0.0;            ///< s: the largest motion per step [d_L]
  double gravity_ = 0.0;           ///< |g|
  double floor_ = 0.0;             ///< the fixed step [t0]
};

}  // namespace confpack::compaction
