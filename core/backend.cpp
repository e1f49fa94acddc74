#include "core/backend.hpp"

#include <stdexcept>
#include <string>

namespace confpack::core {

std::string_view toString(Phase p) {
  switch (p) {
    case Phase::UpdatePairs: return "update_pairs";
    case Phase::Collide: return "collide";
    case Phase::PrepareContacts: return "prepare_contacts";
    case Phase::WarmStart: return "warm_start";
    case Phase::Solve: return "solve";
    case Phase::Integrate: return "integrate";
    case Phase::StoreImpulses: return "store_impulses";
    case Phase::Count: break;
  }
  return "unknown";
}

QuasiStaticMove ContactBackend::quasiStaticStep(double, double) {
  throw std::logic_error(std::string(name()) + ": no quasi-static step");
}

}  // namespace confpack::core
