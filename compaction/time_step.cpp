#include "compaction/time_step.hpp"

#include <algorithm>
#include <cmath>

namespace confpack::compaction {

double defaultTimeStep(const core::RunConfig& cfg, const Deposit& deposit) {
  const double volume = core::totalVolume(deposit.grains);
  const double finalHeight = volume / (cfg.box.lengthX * cfg.box.width * cfg.deposition.expectedSolidFraction);
  const double dh = std::max(deposit.pileHeight - finalHeight, cfg.population.largeSize);
  return 0.01 * std::sqrt(cfg.population.largeSize / (2.0 * dh));
}

AdaptiveTimeStep::AdaptiveTimeStep(const std::vector<core::Grain>& grains, double gravity, double floor)
    : gravity_(gravity), floor_(floor) {
  // Counting a sphere's spin held the step of a 1,648-sphere pile with mu_w = 0.5 at a third of
  // its value without friction.
  spinLever_.reserve(grains.size());
  for (const core::Grain& g : grains) spinLever_.push_back(g.spinLever());
  motion_ = 0.01 * core::smallestSize(grains);
}

double AdaptiveTimeStep::next(double previous, const std::vector<core::BodyState>& states) const {
  if (spinLever_.empty()) return floor_;
  double v = 0.0;
  for (std::size_t i = 0; i < spinLever_.size(); ++i)
    v = std::max(v, states[i].velocity.norm() + states[i].angularVelocity.norm() * spinLever_[i]);
  // v dt + g dt^2 / 2 = s: the positive root, in the form that does not cancel when v^2 >> 2 g s.
  const double dt = 2.0 * motion_ / (v + std::sqrt(v * v + 2.0 * gravity_ * motion_));
  return std::max(floor_, std::min(dt, kAdaptiveGrowth * previous));
}

}  // namespace confpack::compaction
