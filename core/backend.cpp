#include "core/backend.hpp"

#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "core/json_input.hpp"

namespace confpack::core {

std::string unknownBackendMessage(std::string_view name) {
  return fmt::format("unknown backend '{}' (expected nscd or bullet)", textExcerpt(name, 40));
}

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
