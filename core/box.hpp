#pragma once
// The simulation box (docs/model.md, "Box"): periodic along x, side walls (or periodic) along y,
// a floor at z = 0 and a free top. Its geometry only: the walls' friction is WallMaterial's
// (core/walls.hpp). Every module that needs a distance between two
// grains goes through minimumImage() so that periodic images are handled in one place.
#include <cmath>
#include <nlohmann/json_fwd.hpp>

#include "core/types.hpp"

namespace confpack::core {

/// Ids given to the fixed boundaries wherever a contact partner is a wall (docs/packing-format.md).
enum class WallId : int { Floor = -1, SideLow = -2, SideHigh = -3 };

inline constexpr bool isWall(int id) {
  return id < 0;
}

/// Box definition. Lengths in d_L.
struct BoxDef {
  double lengthX = 20.0;   ///< period along x [d_L], > 0
  double width = 10.0;     ///< gap W between the side walls, or period along y [d_L], > 0
  bool periodicY = false;  ///< true: y is periodic with period `width` (no side walls)
  double height = 16.0;    ///< target final packing height h [d_L] (deposition aims for it)

  /// Wraps a position into [0, lengthX) (and [0, width) when periodic in y).
  Vec3 wrap(Vec3 p) const {
    p.x() = wrapCoordinate(p.x(), lengthX);
    if (periodicY) p.y() = wrapCoordinate(p.y(), width);
    return p;
  }

  /// x - L floor(x / L) in [0, L): a tiny negative x rounds to exactly L, which is folded to 0.
  static double wrapCoordinate(double x, double period) {
    const double w = x - period * std::floor(x / period);
    return w >= period ? 0.0 : w;
  }

  /// Minimum-image convention for a separation vector: the shortest periodic copy of d.
  Vec3 minimumImage(Vec3 d) const {
    d.x() -= lengthX * std::nearbyint(d.x() / lengthX);
    if (periodicY) d.y() -= width * std::nearbyint(d.y() / width);
    return d;
  }

  /// Outward-from-the-wall unit normal (pointing into the box) of a wall id.
  static Vec3 wallNormal(WallId w);
  /// A point on the wall plane.
  Vec3 wallPoint(WallId w) const;
  /// Walls present in this box (floor always, side walls unless periodic in y).
  int wallCount() const { return periodicY ? 1 : 3; }
  /// Throws std::invalid_argument with a clear message if a field is not usable.
  void validate() const;
};

template <class T>
class SettingsTable;
/// The keys of BoxDef with units, ranges and meaning (core/settings_table.hpp): its JSON reader
/// and writer and its validation.
const SettingsTable<BoxDef>& boxTable();
void to_json(nlohmann::json& j, const BoxDef& b);
void from_json(const nlohmann::json& j, BoxDef& b);

}  // namespace confpack::core
