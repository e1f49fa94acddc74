#include "core/box.hpp"

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <stdexcept>

namespace confpack::core {

Vec3 BoxDef::wallNormal(WallId w) {
  switch (w) {
    case WallId::Floor: return Vec3::UnitZ();
    case WallId::SideLow: return Vec3::UnitY();
    case WallId::SideHigh: return -Vec3::UnitY();
  }
  return Vec3::UnitZ();
}

Vec3 BoxDef::wallPoint(WallId w) const {
  return w == WallId::SideHigh ? Vec3(0.0, width, 0.0) : Vec3::Zero();
}

void BoxDef::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::invalid_argument(fmt::format("box: {} must be a positive number (got {})", name, v));
  };
  positive(lengthX, "length_x");
  positive(width, "width");
  positive(height, "height");
  if (!(wallFriction >= 0.0) || !std::isfinite(wallFriction))
    throw std::invalid_argument(fmt::format("box: wall_friction must be >= 0 (got {})", wallFriction));
}

void to_json(nlohmann::json& j, const BoxDef& b) {
  j = {{"length_x", b.lengthX},
       {"width", b.width},
       {"periodic_y", b.periodicY},
       {"wall_friction", b.wallFriction},
       {"height", b.height}};
}

void from_json(const nlohmann::json& j, BoxDef& b) {
  BoxDef d;
  b.lengthX = j.value("length_x", d.lengthX);
  b.width = j.value("width", d.width);
  b.periodicY = j.value("periodic_y", d.periodicY);
  b.wallFriction = j.value("wall_friction", d.wallFriction);
  b.height = j.value("height", d.height);
}

}  // namespace confpack::core
