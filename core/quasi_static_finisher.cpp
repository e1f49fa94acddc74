#include "core/quasi_static_finisher.hpp"

#include <algorithm>
#include <stdexcept>

namespace confpack::core {

QuasiStaticFinisher::QuasiStaticFinisher(const CompactionDef& def, double smallestSize, double firstStep)
    : trustRadius_(def.trustRadius * smallestSize),
      settleTolerance_(def.settleTolerance * smallestSize),
      maxStep_(def.finisherMaxStep),
      h_(std::min(firstStep, def.finisherMaxStep)) {
  if (!(h_ > 0.0)) throw std::invalid_argument("quasi-static finisher: the first step must be positive");
}

QuasiStaticMove QuasiStaticFinisher::step(ContactBackend& backend) {
  lastMove_ = backend.quasiStaticStep(h_, trustRadius_);
  lastStep_ = h_;
  ++steps_;
  if (lastMove_.clipped) ++clipped_;
  h_ = std::min(2.0 * h_, maxStep_);
  return lastMove_;
}

}  // namespace confpack::core
