#include "compaction/quasi_static_finisher.hpp"

#include <algorithm>
#include <stdexcept>

namespace confpack::compaction {

QuasiStaticFinisher::QuasiStaticFinisher(const core::CompactionDef& def, double smallestSize, double firstStep)
    : trustRadius_(def.trustRadius * smallestSize),
      settleTolerance_(def.settleTolerance * smallestSize),
      maxStep_(def.finisherMaxStep),
      h_(std::min(firstStep, def.finisherMaxStep)) {
  if (!(h_ > 0.0)) throw std::invalid_argument("quasi-static finisher: the first step must be positive");
}

core::QuasiStaticMove QuasiStaticFinisher::step(core::ContactBackend& backend) {
  lastMove_ = backend.quasiStaticStep(h_, trustRadius_);
  lastStep_ = h_;
  ++steps_;
  if (lastMove_.clipped) ++clipped_;
  h_ = std::min(2.0 * h_, maxStep_);
  return lastMove_;
}

nlohmann::json QuasiStaticFinisher::saveState() const {
  return {{"h", h_},
          {"last_step", lastStep_},
          {"steps", steps_},
          {"clipped_steps", clipped_},
          {"last_displacement", lastMove_.maxDisplacement},
          {"last_clipped", lastMove_.clipped}};
}

void QuasiStaticFinisher::restoreState(const nlohmann::json& state) {
  const auto number = [&](const char* key) {
    if (!state.is_object() || !state.contains(key) || !state[key].is_number() || !(state[key].get<double>() >= 0.0))
      throw std::invalid_argument(std::string("checkpoint: finisher: expected a number >= 0 as ") + key);
    return state[key].get<double>();
  };
  const double h = number("h");
  if (!(h > 0.0)) throw std::invalid_argument("checkpoint: finisher: the next step must be positive");
  if (!state["steps"].is_number_integer() || !state["clipped_steps"].is_number_integer() ||
      !state.value("last_clipped", nlohmann::json()).is_boolean())
    throw std::invalid_argument("checkpoint: finisher: expected whole step counts and last_clipped");
  h_ = h;
  lastStep_ = number("last_step");
  steps_ = static_cast<long>(number("steps"));
  clipped_ = static_cast<long>(number("clipped_steps"));
  lastMove_.maxDisplacement = number("last_displacement");
  lastMove_.clipped = state["last_clipped"].get<bool>();
}

}  // namespace confpack::compaction
