#pragma once
// Builders and independent references shared by the polyhedron tests (tests/collision): the unit
// pinacoid's known planes, random rotations, the conversion to FCL (whose libccd distance is the
// reference for separated pairs) and a brute-force separating-axis test.
#include <fcl/fcl.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "collision/polyhedron_contact.hpp"
#include "core/pinacoid.hpp"

namespace confpack::testing {

inline const core::PinacoidParams kParams{};                           // L = G = E = 1, alpha = 60 deg
inline const double kL = core::pinacoidRidgeHalfLength(1.0, kParams);  // ridge half-length l
// Top trapezoid y > 0 of the unit pinacoid: the plane y + z = 1/2, normal (0,1,1)/sqrt2.
inline const core::Vec3 kN1 = core::Vec3(0, 1, 1).normalized();
inline const double kOff1 = 0.5 / std::sqrt(2.0);

/// A rotation drawn from a normalised Gaussian quaternion (uniform on SO(3)).
inline core::Mat3 randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  core::Quat q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}

/// Whether world point x lies in the placed polyhedron p, allowing tol outside its faces.
inline bool onSurfaceOrInside(const collision::PlacedPolyhedron& p, const core::Vec3& x, double tol) {
  return p.shape->contains(p.rotation.transpose() * (x - p.position), tol);
}

/// Largest signed distance of world point x to the face planes of p: the distance to the surface
/// when x projects inside a face, 0 on the surface, < 0 inside.
inline double signedFacePlaneMax(const collision::PlacedPolyhedron& p, const core::Vec3& x) {
  const core::Vec3 b = p.rotation.transpose() * (x - p.position);
  double m = -1e300;
  for (std::size_t f = 0; f < p.shape->faceNormals().size(); ++f)
    m = std::max(m, p.shape->faceNormals()[f].dot(b) - p.shape->faceOffsets()[f]);
  return m;
}

/// The polyhedron as an FCL convex shape (same vertices and face loops).
inline std::shared_ptr<fcl::Convexd> toFcl(const core::ConvexPolyhedron& p) {
  auto verts = std::make_shared<std::vector<fcl::Vector3d>>(p.vertices().begin(), p.vertices().end());
  auto faces = std::make_shared<std::vector<int>>();
  for (const auto& loop : p.faces()) {
    faces->push_back(static_cast<int>(loop.size()));
    faces->insert(faces->end(), loop.begin(), loop.end());
  }
  return std::make_shared<fcl::Convexd>(verts, static_cast<int>(p.faces().size()), faces);
}

/// Independent minimum-penetration check: max over ALL face normals and ALL edge-pair cross
/// products (no Gauss-map pruning) of the support separation min_B u.x - max_A u.x.
inline double bruteForceSat(const collision::PlacedPolyhedron& a, const collision::PlacedPolyhedron& b) {
  const auto va = a.worldVertices(), vb = b.worldVertices();
  auto sep = [&](core::Vec3 u) {
    double maxA = -1e300, minB = 1e300;
    for (const core::Vec3& x : va) maxA = std::max(maxA, u.dot(x));
    for (const core::Vec3& x : vb) minB = std::min(minB, u.dot(x));
    double s1 = minB - maxA;
    double maxB = -1e300, minA = 1e300;
    for (const core::Vec3& x : vb) maxB = std::max(maxB, u.dot(x));
    for (const core::Vec3& x : va) minA = std::min(minA, u.dot(x));
    return std::max(s1, minA - maxB);  // either orientation of the axis
  };
  double best = -1e300;
  for (const core::Vec3& n : a.shape->faceNormals()) best = std::max(best, sep(a.rotation * n));
  for (const core::Vec3& n : b.shape->faceNormals()) best = std::max(best, sep(b.rotation * n));
  for (const auto& ea : a.shape->edges())
    for (const auto& eb : b.shape->edges()) {
      const core::Vec3 u = (va[ea[1]] - va[ea[0]]).cross(vb[eb[1]] - vb[eb[0]]);
      if (u.norm() > 1e-9) best = std::max(best, sep(u.normalized()));
    }
  return best;
}

}  // namespace confpack::testing
