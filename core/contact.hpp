#pragma once
// A contact as backends report it and analysis reads it (docs/model.md, "Contact backends";
// docs/packing-format.md).
//
// Conventions, the same everywhere:
// - `a` is a grain index; `b` is a grain index or a wall id (WallId, negative).
// - `normal` is the unit normal pointing from a towards b (for a wall: into the wall, i.e.
//   minus the wall's inward normal).
// - Forces, not impulses: a backend reports the mean force over its last step (impulse / dt), so
//   packings, analysis and both backends share one unit [m g]. A normal force f_n >= 0 pushes b
//   along +normal and a along -normal.
// - Points are in world coordinates near grain a's actual position (not wrapped): for a pair
//   across a periodic boundary, b's lever arm is box.minimumImage(point - b.position).
#include <string_view>
#include <vector>

#include "core/types.hpp"

namespace confpack::core {

/// Geometric type of a contact (docs/model.md, "Coordination number"): vertex-face or crossing
/// edges -> Simple (1 point), edge-face or two edges lying along each other -> Double (2 points),
/// face-face -> Triple (3+ points from the face intersection). Sphere contacts are Simple.
enum class ContactType { Simple, Double, Triple };

std::string_view toString(ContactType t);
ContactType contactTypeFromString(std::string_view s);  ///< throws std::invalid_argument

struct ContactPoint {
  Vec3 position = Vec3::Zero();      ///< world frame, near grain a
  double normalForce = 0.0;          ///< f_n >= 0, mean over the last step [rho g d_L^3]
  Vec3 tangentForce = Vec3::Zero();  ///< friction force on b (orthogonal to normal); walls only
  double gap = 0.0;                  ///< signed gap at detection (negative = overlap) [d_L]
};

struct Contact {
  int a = 0;
  int b = 0;
  ContactType type = ContactType::Simple;
  Vec3 normal = Vec3::UnitZ();
  std::vector<ContactPoint> points;

  /// Sum of the normal forces of all points.
  double normalForce() const {
    double s = 0.0;
    for (const auto& p : points) s += p.normalForce;
    return s;
  }
  /// Total force applied on b (minus that on a).
  Vec3 forceOnB() const {
    Vec3 s = Vec3::Zero();
    for (const auto& p : points) s += p.normalForce * normal + p.tangentForce;
    return s;
  }
};

}  // namespace confpack::core
