#include "core/walls.hpp"

#include "core/settings_table.hpp"

namespace confpack::core {

const SettingsTable<WallMaterial>& wallMaterialTable() {
  static const SettingsTable<WallMaterial> table = [] {
    SettingsTable<WallMaterial> t("walls");
    t.number("friction", &WallMaterial::friction, Range::atLeast(0.0), "-",
             "Coulomb friction mu_w of the side walls; the floor is frictionless");
    return t;
  }();
  return table;
}

void WallMaterial::validate() const {
  wallMaterialTable().validate(*this);
}

void readLegacyWallFriction(const nlohmann::json& value, WallMaterial& walls) {
  try {
    wallMaterialTable().readKey("friction", value, walls);
  } catch (const std::invalid_argument& e) {  // "walls.friction: ..." as the document spells it
    const std::string what = e.what(), key = "walls.friction";
    throw std::invalid_argument("box.wall_friction" +
                                (what.rfind(key, 0) == 0 ? what.substr(key.size()) : ": " + what));
  }
}

void to_json(nlohmann::json& j, const WallMaterial& w) {
  j = wallMaterialTable().write(w);
}

void from_json(const nlohmann::json& j, WallMaterial& w) {
  w = WallMaterial{};
  wallMaterialTable().read(j, w);
}

}  // namespace confpack::core
