#include "core/box.hpp"

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/settings_table.hpp"

namespace confpack::core {

Vec3 BoxDef::wallNormal(WallId w) {
  switch (w) {
    case WallId::Floor:
      return Vec3::UnitZ();
    case WallId::SideLow:
      return Vec3::UnitY();
    case WallId::SideHigh:
      return -Vec3::UnitY();
  }
  return Vec3::UnitZ();
}

Vec3 BoxDef::wallPoint(WallId w) const {
  return w == WallId::SideHigh ? Vec3(0.0, width, 0.0) : Vec3::Zero();
}

const SettingsTable<BoxDef>& boxTable() {
  static const SettingsTable<BoxDef> table = [] {
    SettingsTable<BoxDef> t("box");
    t.number("length_x", &BoxDef::lengthX, Range::positive(), "d_L", "period along x")
        .number("width", &BoxDef::width, Range::positive(), "d_L", "gap W between the side walls, or period along y")
        .flag("periodic_y", &BoxDef::periodicY, "y periodic with period width (no side walls)")
        .number("height", &BoxDef::height, Range::positive(), "d_L",
                "target final packing height (deposition aims for it)");
    return t;
  }();
  return table;
}

void BoxDef::validate() const {
  boxTable().validate(*this);
}

void to_json(nlohmann::json& j, const BoxDef& b) {
  j = boxTable().write(b);
}

void from_json(const nlohmann::json& j, BoxDef& b) {
  b = BoxDef{};
  boxTable().read(j, b);
}

}  // namespace confpack::core
