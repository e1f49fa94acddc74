#pragma once
// Test builders shared by every test folder: a sphere, a pinacoid, a grain moved so that its
// lowest vertex sits at a given height, and an empty system in a box. Both grain builders take
// (size, position[, orientation]) in that order.
#include <algorithm>
#include <string>

#include "core/backend.hpp"
#include "core/run_config.hpp"

namespace confpack::testing {

/// A sphere of diameter d at p (at rest, identity orientation).
inline core::Grain sphere(double d, const core::Vec3& p) {
  core::Grain g;
  g.shape = core::ShapeKind::Sphere;
  g.size = d;
  g.position = p;
  return g;
}

/// A pinacoid of size `size` (default shape parameters: G = E = 1, alpha = 60 deg) centred at p
/// with orientation q (body to world).
inline core::Grain pinacoid(double size, const core::Vec3& p, const core::Quat& q = core::Quat::Identity()) {
  core::Grain g;
  g.shape = core::ShapeKind::Pinacoid;
  g.size = size;
  g.position = p;
  g.orientation = q;
  return g;
}

/// Height of a pinacoid's lowest vertex.
inline double bottomOf(const core::Grain& g) {
  double zMin = 1e300;
  for (const core::Vec3& v : g.worldVertices()) zMin = std::min(zMin, v.z());
  return zMin;
}

/// Height of a pinacoid's highest vertex.
inline double topOf(const core::Grain& g) {
  double zMax = -1e300;
  for (const core::Vec3& v : g.worldVertices()) zMax = std::max(zMax, v.z());
  return zMax;
}

/// The pinacoid g moved vertically so that its lowest vertex is at height zBottom.
inline core::Grain withBottomAt(core::Grain g, double zBottom) {
  g.position.z() += zBottom - bottomOf(g);
  return g;
}

/// A system with no grains in a box of length lengthX and width W (periodic or walled in y)
/// with side-wall friction mu; default gravity and density.
inline core::SystemDef boxSystem(double lengthX, double width, bool periodicY, double mu) {
  core::SystemDef s;
  s.box.lengthX = lengthX;
  s.box.width = width;
  s.box.periodicY = periodicY;
  s.walls.friction = mu;
  return s;
}

/// A run of the quasi-static protocol on a small walled pile (L_x = 4, W = 3, h = 4, about 40
/// spheres, seed 2), checked every 50 steps: the compaction tests' pile, a few seconds to rest.
inline core::RunConfig smallQuasiStaticRun(const std::string& backend, double wallFriction) {
  core::RunConfig cfg;
  cfg.box.lengthX = 4.0;
  cfg.box.width = 3.0;
  cfg.box.height = 4.0;
  cfg.walls.friction = wallFriction;
  cfg.backend = backend;
  cfg.seed = 2;
  cfg.compaction.protocol = core::Protocol::QuasiStatic;
  cfg.compaction.timeLimit = 40.0;
  cfg.compaction.checkInterval = 50;
  return cfg;
}

}  // namespace confpack::testing
