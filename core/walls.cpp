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

void to_json(nlohmann::json& j, const WallMaterial& w) {
  j = wallMaterialTable().write(w);
}

void from_json(const nlohmann::json& j, WallMaterial& w) {
  w = WallMaterial{};
  wallMaterialTable().read(j, w);
}

}  // namespace confpack::core
