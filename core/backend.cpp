#include "core/backend.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/json_input.hpp"

namespace confpack::core {

std::string unknownBackendMessage(std::string_view name) {
  return fmt::format("unknown backend '{}' (expected nscd or bullet)", textExcerpt(name, 40));
}

std::string_view toString(Phase p) {
  switch (p) {
    case Phase::UpdatePairs:
      return "update_pairs";
    case Phase::Collide:
      return "collide";
    case Phase::PrepareContacts:
      return "prepare_contacts";
    case Phase::WarmStart:
      return "warm_start";
    case Phase::Solve:
      return "solve";
    case Phase::Integrate:
      return "integrate";
    case Phase::StoreImpulses:
      return "store_impulses";
    case Phase::Count:
      break;
  }
  return "unknown";
}

QuasiStaticMove ContactBackend::quasiStaticStep(double, double) {
  throw std::logic_error(std::string(name()) + ": no quasi-static step");
}

nlohmann::json ContactBackend::saveState() const {
  return {{"grains", bodyStatesToJson(states())}};
}

nlohmann::json bodyStatesToJson(const std::vector<BodyState>& states) {
  nlohmann::json out = nlohmann::json::array();
  for (const BodyState& s : states) {
    const Quat& q = s.orientation;
    out.push_back({s.position.x(), s.position.y(), s.position.z(), q.w(), q.x(), q.y(), q.z(), s.velocity.x(),
                   s.velocity.y(), s.velocity.z(), s.angularVelocity.x(), s.angularVelocity.y(),
                   s.angularVelocity.z()});
  }
  return out;
}

std::vector<BodyState> bodyStatesFromJson(const nlohmann::json& j, std::size_t count) {
  if (!j.is_array() || j.size() != count)
    throw std::invalid_argument(fmt::format("checkpoint: expected the states of {} grains", count));
  std::vector<BodyState> states(count);
  for (std::size_t i = 0; i < count; ++i) {
    const nlohmann::json& g = j[i];
    double x[13];
    if (!g.is_array() || g.size() != 13)
      throw std::invalid_argument(fmt::format("checkpoint: grain {}: expected 13 numbers", i));
    for (std::size_t k = 0; k < 13; ++k) {
      if (!g[k].is_number() || !std::isfinite(g[k].get<double>()))
        throw std::invalid_argument(fmt::format("checkpoint: grain {}: not a finite number", i));
      x[k] = g[k].get<double>();
    }
    states[i].position = Vec3(x[0], x[1], x[2]);
    states[i].orientation = Quat(x[3], x[4], x[5], x[6]);
    states[i].velocity = Vec3(x[7], x[8], x[9]);
    states[i].angularVelocity = Vec3(x[10], x[11], x[12]);
  }
  return states;
}

}  // namespace confpack::core
