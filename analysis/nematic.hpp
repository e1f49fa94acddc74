#pragma once
// Nematic order of pinacoids (docs/model.md, "Order").
//
// With u, v, w the unit principal axes of a grain (the body x, y, z axes of the pinacoid, which
// are principal axes by its three mirror planes; world columns of its rotation matrix),
//   Q^uu = (1/n) sum (3/2 u u^T - 1/2 I), and likewise Q^vv, Q^ww.
// The director Z is the eigenvector of the largest eigenvalue among the three tensors and
// Q00^2 = Z^T Q Z for that tensor, i.e. that largest eigenvalue. Q00^2 = 1 for perfectly aligned
// grains; for n random orientations it is O(1/sqrt n).
// Groups: boundary layers = grains of the bulk region (centre height) whose centre is within
// `boundaryDistance` (2 d_L) of a side wall; bulk = the other grains of the bulk region.
// Spheres, a biperiodic box (no boundary layer) or an empty group give no value.
#include <optional>
#include <vector>

#include "analysis/bulk_region.hpp"

namespace confpack::analysis {

struct NematicOrder {
  double q00 = 0.0;  ///< Q00^2, the largest eigenvalue [-]
  int axis = 0;      ///< 0: u (length), 1: v (width), 2: w (height)
  core::Vec3 director = core::Vec3::UnitZ();
  int grains = 0;
};

/// Nematic order of a set of body-to-world rotations.
NematicOrder nematicOrder(const std::vector<core::Mat3>& rotations);

struct Nematic {
  std::optional<NematicOrder> bulk;
  std::optional<NematicOrder> boundary;
};

Nematic nematic(const core::Packing& packing, const BulkRegion& region, double boundaryDistance = 2.0);

}  // namespace confpack::analysis
