#pragma once
// Fabric of the contact network (docs/model.md, "Order").
//
// Anisotropy. F = (1/N) sum n (x) n over unit branch vectors (centre to centre, minimum image) of
// the force-carrying grain-grain contacts, each weighted by the share of its two grains that are
// in the bulk region (1, or 1/2 for a contact leaving the bulk: the same per-grain counting as Z,
// so that a lattice cut by the region boundaries keeps its exact fabric); eigenvalues
// F1 >= F2 >= F3; a = (5/2)(F1 - F3). For a density P(n) = (1 + a (3 cos^2 theta - 1)) / 4 pi
// about the axis of F1, <cos^2> = 1/3 + 4a/15 and the two others 1/3 - 2a/15, so F1 - F3 = 2a/5
// and the estimator returns a. Isotropic directions give a ~ O(1/sqrt N) (never exactly 0).
//
// Orientation distributions of contact normals, per contact type: the angle to the vertical
// binned in cos(theta) = |n_z| over [0, 1] (uniform bins in |n_z| are uniform in solid angle, so
// an isotropic network gives a flat histogram and P ~ 1 + a(3 cos^2 - 1) shows directly), and the
// azimuth atan2(n_y, n_x) folded to [0, 180) degrees (n and -n are the same contact). Each
// histogram is a density normalised to mean 1 over its bins (0 when it has no contact), with the
// same contact weights.
#include <array>
#include <vector>

#include "analysis/coordination.hpp"

namespace confpack::analysis {

struct FabricDef {
  int cosBins = 10;      ///< bins of |n_z| over [0, 1], >= 1
  int azimuthBins = 18;  ///< bins of the azimuth over [0, 180) deg, >= 1
  void validate() const;
};

struct OrientationHistogram {
  std::vector<double> cosTheta;  ///< density per |n_z| bin (mean 1)
  std::vector<double> azimuth;   ///< density per azimuth bin (mean 1)
  int count = 0;                 ///< contacts in the histogram (unweighted)
};

struct Fabric {
  core::Mat3 tensor = core::Mat3::Zero();       ///< F
  core::Vec3 eigenvalues = core::Vec3::Zero();  ///< F1 >= F2 >= F3
  core::Vec3 majorAxis = core::Vec3::UnitZ();   ///< eigenvector of F1
  double anisotropy = 0.0;                      ///< a = (5/2)(F1 - F3)
  int contacts = 0;
  /// Index 0..2 = Simple, Double, Triple; index 3 = all types together.
  std::array<OrientationHistogram, 4> orientation;
};

/// Fabric of directions (normalised here), optionally weighted (empty = all 1); the orientation
/// histograms are left empty.
Fabric fabricOfDirections(const std::vector<core::Vec3>& directions, const std::vector<double>& weights = {});

/// Fabric of the counted contacts touching the bulk region.
Fabric fabric(const core::Packing& packing, const BulkRegion& region, const std::vector<CountedContact>& counted,
              const FabricDef& def = {});

}  // namespace confpack::analysis
