#pragma once
// Shared small types. Eigen supplies the linear algebra; everything is double precision and
// dimensionless (d_L = 1, g = 1, rho = 1; docs/model.md, "Units").
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace confpack::core {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

}  // namespace confpack::core
