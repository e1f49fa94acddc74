#pragma once
// The pinacoid (docs/model.md, "Pinacoids"): 8 vertices, 14 edges, 8 faces (4 isosceles triangles,
// 4 isosceles trapezoids), three mirror planes. Body frame: centroid at the origin, length L along
// x, width G along y, height E along z.
//
//   mid-plane rectangle: (+-L/2, +-G/2, 0)
//   ridge ends:          (+-l, 0, +-E/2),   l = L/2 - (E/2)/tan(alpha)
//
// alpha is the inclination of the triangular end faces on the mid-plane. The published figure
// could not be read; this is the project's reading and stays a documented parameter.
#include <nlohmann/json_fwd.hpp>

#include "core/convex_polyhedron.hpp"

namespace confpack::core {

/// Shape parameters relative to the length L (= the grain's size).
struct PinacoidParams {
  double widthRatio = 1.0;   ///< G / L [-]
  double heightRatio = 1.0;  ///< E / L [-]
  double alphaDeg = 60.0;    ///< inclination of the triangular faces [degrees], in (0, 90)

  /// Throws std::invalid_argument unless 0 < l < L/2 (a proper pinacoid with a ridge).
  void validate() const;
  bool operator==(const PinacoidParams&) const = default;
};

template <class T>
class SettingsTable;
/// The keys of PinacoidParams (core/settings_table.hpp): JSON reader, writer and validation.
const SettingsTable<PinacoidParams>& pinacoidTable();
void to_json(nlohmann::json& j, const PinacoidParams& p);  // {"G":..,"E":..,"alpha_deg":..}
void from_json(const nlohmann::json& j, PinacoidParams& p);

/// Half-length of the ridge, l = L/2 - (E/2)/tan(alpha), for length L.
double pinacoidRidgeHalfLength(double length, const PinacoidParams& p);
/// The pinacoid of length L (size) in its body frame.
ConvexPolyhedron makePinacoid(double length, const PinacoidParams& p);
/// Closed-form mass properties (docs/model.md, "Pinacoids"; density rho): volume, centroid 0,
/// second moments.
MassProperties pinacoidMassProperties(double length, const PinacoidParams& p);

}  // namespace confpack::core
