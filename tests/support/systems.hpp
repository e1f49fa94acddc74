#pragma once
// Test helpers shared by the backend tests: a sphere grain, a pinacoid placed by its lowest
// vertex, and an empty system in a box.
#include <algorithm>

#include "core/backend.hpp"

namespace confpack::testing {

/// A sphere of diameter d at p (at rest, identity orientation).
inline core::Grain sphere(double d, const core::Vec3& p) {
  core::Grain g;
  g.shape = core::ShapeKind::Sphere;
  g.size = d;
  g.position = p;
  return g;
}

/// A unit pinacoid (G = E = 1, alpha = 60 deg) with orientation q, centred at (x, y), its lowest
/// vertex at height zBottom.
inline core::Grain pinacoid(const core::Quat& q, double x, double y, double zBottom) {
  core::Grain g;
  g.shape = core::ShapeKind::Pinacoid;
  g.size = 1.0;
  g.orientation = q;
  g.position = core::Vec3(x, y, 0.0);
  double zMin = 1e300;
  for (const core::Vec3& v : g.worldVertices()) zMin = std::min(zMin, v.z());
  g.position.z() = zBottom - zMin;
  return g;
}

/// Height of a grain's highest vertex.
inline double topOf(const core::Grain& g) {
  double zMax = -1e300;
  for (const core::Vec3& v : g.worldVertices()) zMax = std::max(zMax, v.z());
  return zMax;
}

/// A system with no grains in a box of length lengthX and width W (periodic or walled in y)
/// with side-wall friction mu; default gravity and density.
inline core::SystemDef boxSystem(double lengthX, double width, bool periodicY, double mu) {
  core::SystemDef s;
  s.box.lengthX = lengthX;
  s.box.width = width;
  s.box.periodicY = periodicY;
  s.box.wallFriction = mu;
  return s;
}

}  // namespace confpack::testing
