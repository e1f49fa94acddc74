#include "analysis/nematic.hpp"

#include <Eigen/Eigenvalues>

namespace confpack::analysis {

NematicOrder nematicOrder(const std::vector<core::Mat3>& rotations) {
  NematicOrder r;
  r.grains = static_cast<int>(rotations.size());
  if (rotations.empty()) return r;
  bool first = true;
  for (int axis = 0; axis < 3; ++axis) {
    core::Mat3 q = core::Mat3::Zero();
    for (const core::Mat3& rot : rotations) {
      const core::Vec3 u = rot.col(axis).normalized();
      q += 1.5 * u * u.transpose() - 0.5 * core::Mat3::Identity();
    }
    q /= static_cast<double>(rotations.size());
    const Eigen::SelfAdjointEigenSolver<core::Mat3> es(q);
    if (first || es.eigenvalues()(2) > r.q00) {
      r.q00 = es.eigenvalues()(2);
      r.director = es.eigenvectors().col(2);
      r.axis = axis;
      first = false;
    }
  }
  return r;
}

Nematic nematic(const core::Packing& packing, const BulkRegion& region, double boundaryDistance) {
  Nematic out;
  std::vector<core::Mat3> bulk, boundary;
  const core::BoxDef& box = packing.box;
  for (const core::Grain& g : packing.grains) {
    if (g.shape != core::ShapeKind::Pinacoid || !region.contains(g.position.z())) continue;
    const core::Mat3 rot = g.orientation.normalized().toRotationMatrix();
    const bool nearWall = !box.periodicY && std::min(g.position.y(), box.width - g.position.y()) < boundaryDistance;
    (nearWall ? boundary : bulk).push_back(rot);
  }
  if (!bulk.empty()) out.bulk = nematicOrder(bulk);
  if (!boundary.empty()) out.boundary = nematicOrder(boundary);
  return out;
}

}  // namespace confpack::analysis
