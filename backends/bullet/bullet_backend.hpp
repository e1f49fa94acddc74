#pragma once
// No Bullet header here: the implementation is a pimpl in bullet_backend.cpp so that
// BT_USE_DOUBLE_PRECISION never reaches the rest of the code.
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/backend.hpp"

namespace confpack::bullet {

/// Bullet's sequential-impulse solver behind the backend interface (docs/model.md, "Bullet:
/// sequential impulses").
/// `options`: the keys of BulletSettings (backends/bullet/bullet_settings.hpp); unknown keys and
/// out-of-range values throw std::invalid_argument, as does a system Bullet cannot represent
/// (a box shorter than one grain along a periodic direction, a non-positive size).
std::unique_ptr<core::ContactBackend> makeBulletBackend(const core::SystemDef& system, const nlohmann::json& options);

/// Read-only views of Bullet's internals for tests; they throw std::invalid_argument when
/// `backend` is not a bullet backend. Nothing here exposes a Bullet type.
namespace inspect {

/// The support points of grain `grain`'s collision shape as Bullet simulates it
/// (btConvexShape::localGetSupportingVertex, margin included), one per body-frame direction,
/// in the body frame [d_L].
std::vector<core::Vec3> supportPoints(const core::ContactBackend& backend, int grain,
                                      const std::vector<core::Vec3>& bodyDirections);

/// The friction coefficient Bullet's solver used (btManifoldPoint::m_combinedFriction) for every
/// point of the last step's manifold between a and b (b may be a wall id), whether that manifold
/// came from Bullet's broad phase or from a periodic image. Empty if there is none.
std::vector<double> combinedFriction(const core::ContactBackend& backend, int a, int b);

/// The collision margin of grain `grain`'s shape [d_L] (0 for a hull: nothing inflates it; the
/// radius for a sphere, which Bullet models as a point plus its margin).
double collisionMargin(const core::ContactBackend& backend, int grain);

}  // namespace inspect

}  // namespace confpack::bullet
