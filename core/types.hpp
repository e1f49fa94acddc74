#pragma once
// Shared small types. Eigen supplies the linear algebra; everything is double precision and
// dimensionless (d_L = 1, g = 1, rho = 1; docs/model.md, "Units").
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace confpack::core {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

/// Skew-symmetric matrix [a]x such that [a]x b = a x b.
inline Mat3 crossMatrix(const Vec3& a) {
  Mat3 m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

}  // namespace confpack::core
