#pragma once
// Independent check of the sphere solid fraction by a radical Voronoi tessellation (docs/model.md,
// "Solid fraction"), with voro++ (container_poly: cells weighted by the
// radii, so that a cell holds its whole sphere even in a polydisperse packing).
//
//   phi_voronoi = (sum of the volumes of the bulk spheres) / (sum of their radical cells),
// bulk spheres = centre in the bulk region. The container is the box: periodic along x (and y
// when biperiodic), cut by the side walls, by the floor and by a ceiling 1 d_L above the highest
// grain (cells touching the ceiling are far above the bulk). It is a grain-centred estimator,
// not the slab volume of solid_fraction: the two agree exactly on lattices aligned with the
// region and to within the boundary noise of a few grain layers on disordered packings.
#include <optional>

#include "analysis/bulk_region.hpp"

namespace confpack::analysis {

struct VoronoiFraction {
  double phi = 0.0;  ///< bulk sphere volume / bulk cell volume [-]
  int cells = 0;     ///< bulk spheres whose cell was computed
};

/// nullopt for a packing that is not all spheres, an empty bulk, or a build without voro++.
std::optional<VoronoiFraction> voronoiSolidFraction(const core::Packing& packing, const BulkRegion& region);

}  // namespace confpack::analysis
