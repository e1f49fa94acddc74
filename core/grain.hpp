#pragma once
// A grain as every module sees it: shape, size, pose. Mass properties are derived (rho = 1 by
// default), never stored, so a packing file only needs shape, size, params, position, orientation.
#include <nlohmann/json_fwd.hpp>
#include <string_view>
#include <vector>

#include "core/pinacoid.hpp"

namespace confpack::core {

enum class ShapeKind { Sphere, Pinacoid };

std::string_view toString(ShapeKind s);
/// "sphere" or "pinacoid"; throws std::invalid_argument otherwise.
ShapeKind shapeFromString(std::string_view s);

struct Grain {
  ShapeKind shape = ShapeKind::Sphere;
  double size = 1.0;                    ///< sphere diameter d, or pinacoid length L [d_L]
  PinacoidParams params{};              ///< used when shape == Pinacoid
  Vec3 position = Vec3::Zero();         ///< centroid, world frame [d_L]
  Quat orientation = Quat::Identity();  ///< body-to-world rotation

  double volume() const;
  /// Body-frame inertia about the centroid for density rho.
  Mat3 bodyInertia(double density = 1.0) const;
  /// Radius of the smallest centred sphere enclosing the grain.
  double boundingRadius() const;
  /// Whether a rotation about the centroid moves the grain's boundary: not a sphere's. With wall
  /// friction a sphere leaves the wall spinning and keeps that spin for ever (its other contacts
  /// are frictionless), so the spin must not count as motion that can change the packing.
  bool spinMovesBoundary() const { return shape != ShapeKind::Sphere; }
  /// How far the boundary moves per radian of rotation at most: the bounding radius, 0 for a sphere
  /// (spinMovesBoundary). A grain's surface moves at most |v| + |omega| spinLever().
  double spinLever() const { return spinMovesBoundary() ? boundingRadius() : 0.0; }
  /// Body-frame polyhedron (pinacoids only).
  ConvexPolyhedron polyhedron() const;
  /// World-frame vertices of a pinacoid.
  std::vector<Vec3> worldVertices() const;
};

/// Solid material volume of all grains.
double totalVolume(const std::vector<Grain>& grains);
/// The smallest grain size (diameter or pinacoid length) [d_L]; +infinity for no grains.
double smallestSize(const std::vector<Grain>& grains);

}  // namespace confpack::core
