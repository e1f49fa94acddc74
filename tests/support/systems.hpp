#pragma once
// Test helpers shared by the backend tests: a sphere grain and an empty system in a box.
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
