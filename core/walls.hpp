#pragma once
// The walls' material (docs/model.md, "Box"): what a contact with a wall feels, apart from where
// the walls are (BoxDef). The floor is frictionless; the two side walls carry Coulomb friction
// mu_w, the confinement's one material parameter.
#include <nlohmann/json_fwd.hpp>

#include "core/box.hpp"

namespace confpack::core {

struct WallMaterial {
  double friction = 0.0;  ///< Coulomb friction mu_w of the side walls [-]; 0: frictionless, as the floor

  /// The friction coefficient of a contact with wall `w`: 0 on the floor, mu_w on a side wall.
  double frictionOf(WallId w) const { return w == WallId::Floor ? 0.0 : friction; }
  void validate() const;  ///< throws std::invalid_argument naming the bad key
  bool operator==(const WallMaterial&) const = default;
};

template <class T>
class SettingsTable;
/// The keys of WallMaterial (config.json's "walls"; core/settings_table.hpp).
const SettingsTable<WallMaterial>& wallMaterialTable();
/// Reads `value`, given as box.wall_friction (the packing file's spelling, and config.json's
/// before the walls had their own object), into walls.friction; errors name box.wall_friction.
void readLegacyWallFriction(const nlohmann::json& value, WallMaterial& walls);
void to_json(nlohmann::json& j, const WallMaterial& w);
void from_json(const nlohmann::json& j, WallMaterial& w);

}  // namespace confpack::core
