#pragma once
// All per-run measurements on one packing, as the result.json blocks and the CSV profiles
// (docs/model.md, from "Bulk region and free surface" to "Coordination number", and "Results").
// Read-only over the packing; the same code for both backends.
//
// Contacts: the packing's own list when it has one (a run: forces of the last step), otherwise
// geometric contacts (analysis/geometric_contacts.hpp, all force-carrying).
// Equilibrium: the run pipeline adds its own block (it has the velocities). Here, when the packing
// carries contacts with forces and `equilibrium` is on, the equilibrium test is evaluated with all
// velocities taken as zero ("velocities": "assumed_zero" in the block): the force and moment
// balances are then exact, the kinetic ratio is 0 by assumption. Without contacts the block is
// null (there are no forces to balance).
// Two readings (docs/model.md, "Two readings of a packing"), the exact one the default and always
// reported: `inflate` S > 1 analyses instead the packing with every grain scaled by S about its
// centroid (analysis/inflate.hpp), every block of it (phi from the scaled volumes, the
// interpenetration, the contacts, found geometrically, and their types) but the equilibrium test,
// which weighs the forces on the grains as they are; the homogeneity's size threshold is scaled
// with the grains, so that a grain keeps its size class. `typeBand` B > 0 adds the coordination
// with the contact types read by a tolerance band of B x the grain size (analysis/coordination.hpp)
// beside the exact one.
// Profile fit: only with side walls (a biperiodic box has no wall profile); bidisperse law when
// the packing holds both large and small grains (homogeneity's size threshold).
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>

#include "analysis/bulk_region.hpp"
#include "analysis/coordination.hpp"
#include "analysis/equilibrium.hpp"
#include "analysis/fabric.hpp"
#include "analysis/geometric_contacts.hpp"
#include "analysis/geometric_model.hpp"
#include "analysis/homogeneity.hpp"
#include "analysis/inflate.hpp"
#include "analysis/interpenetration.hpp"
#include "analysis/nematic.hpp"
#include "analysis/profile_fit.hpp"
#include "analysis/rigidity.hpp"
#include "analysis/solid_fraction.hpp"
#include "analysis/voronoi.hpp"

namespace confpack::analysis {

struct AnalysisOptions {
  BulkRegionDef region{};
  ProfileDef profile{};
  InterpenetrationDef interpenetration{};
  CoordinationDef coordination{};
  GeometricContactDef geometricContacts{};
  FabricDef fabric{};
  HomogeneityDef homogeneity{};
  ProfileFitDef profileFit{};                       ///< `bidisperse` is decided from the grains
  double boundaryDistance = 2.0;                    ///< nematic boundary layer thickness [d_L]
  bool voronoi = true;                              ///< radical Voronoi check of sphere packings
  bool equilibrium = true;                          ///< equilibrium test (zero velocities) when forces are present
  core::Vec3 gravity = core::Vec3(0.0, 0.0, -1.0);  ///< [g]
  double density = 1.0;                             ///< rho
  double forceRatio = 1e-4, momentRatio = 1e-4, kineticRatio = 1e-8;  ///< equilibrium thresholds
  /// Most cells the profiles and the free-surface grid may take (estimatedCells), a guard against a
  /// slice or cell typed far too small (`analyze --slice 1e-7` on 170 grains: over 10 minutes and
  /// 3.7 GB) [-]. 2e8 bounds the slowest analysis per cell (few grains, thin slices: the profile
  /// fit) to about a minute: 55 s and 120 MB for 170 grains x 1.2e6 slices, against 25 s at 1e8 and
  /// 6.4 min (554 MB) at 1e9. The default slice on 30,400 grains across W = 40 is 6e7 cells, and
  /// 263,000 grains (1.6e9 cells) took 13 s.
  double maxCells = 2e8;
  /// Every grain scaled by this about its centroid before the analysis (analysis/inflate.hpp) [-],
  /// in [1, kMaxInflation]. 1: the packing as it is, the exact reading a solver's packing needs.
  double inflate = 1.0;
  /// Contact types read also by a tolerance band of this fraction of the grain size
  /// (analysis/coordination.hpp) [-], in (0, kMaxTypeBand]; 0: off, the exact types only.
  double typeBand = 0.0;

  void validate() const;  ///< throws std::invalid_argument naming the bad field
};

/// Everything measured on one packing.
struct Analysis {
  int grains = 0;
  double meanSize = 0.0;  ///< d_avg [d_L]
  bool bidisperse = false;
  BulkRegion region;
  SolidFraction solid;
  std::optional<VoronoiFraction> voronoi;  ///< radical Voronoi check (spheres with voro++)
  SolidFractionProfile phiProfile;
  ProfileFit profileFit;                   ///< ok = false with a reason when absent
  std::optional<double> profileIntegralC;  ///< 2 int (phi_bulk - phi(y)) dy with the fitted phi_bulk
  Interpenetration interpenetration;
  double inflate = 1.0;  ///< the grains' scale factor of this reading [-] (1: as they are)
  bool geometricContacts = false;
  Coordination coordination;
  double typeBand = 0.0;                         ///< the band of coordinationBand [grain size], 0: none
  std::optional<Coordination> coordinationBand;  ///< the types by the tolerance band (options.typeBand > 0)
  std::optional<Rigidity> rigidity;              ///< between frictionless walls (rigidity.hpp)
  Fabric fabric;
  Nematic nematic;
  Homogeneity homogeneity;
  std::optional<EquilibriumReport> equilibrium;
};

/// Cells the analysis of `packing` visits with `options`, the largest of: grains x phi(y) slices
/// (each grain's slab volumes are computed over every slice), the Z(y) slices and the cells of the
/// free-surface grid. `what` (if given) receives which one it is.
double estimatedCells(const core::Packing& packing, const AnalysisOptions& options, std::string* what = nullptr);
/// The same for `grains` grains in `box`, known before a packing exists (a run's estimate).
double estimatedCells(const core::BoxDef& box, double grains, const AnalysisOptions& options,
                      std::string* what = nullptr);

/// Throws std::invalid_argument naming the largest count when the analysis of `grains` grains in
/// `box` would visit more than options.maxCells cells: what `run` and `sweep` check before they
/// deposit, so that an oversized run is refused before its work rather than after its compaction.
/// `remedy` ends the message: what the caller's user can change.
void checkCells(const core::BoxDef& box, double grains, const AnalysisOptions& options,
                std::string_view remedy = "check the slice or cell size, or raise the limit with --max-cells");

/// Runs every measurement. Throws std::invalid_argument for an unusable packing (e.g. a contact
/// with an out-of-range grain, mixed sphere-pinacoid pairs), bad options, or more cells than
/// options.maxCells (estimatedCells), before any work.
Analysis analyze(const core::Packing& packing, const AnalysisOptions& options = {});

/// The result.json blocks (docs/model.md, "Results"): n_grains, inflate, free_surface, bulk_region,
/// solid_fraction, coordination, coordination_band (null when off), rigidity,
/// interpenetration_percent, anisotropy, fabric, nematic, profile_fit, equilibrium (null when not
/// evaluated). Quantities that do not apply are null, not absent.
nlohmann::json toJson(const Analysis& a);

/// analyze() + toJson().
nlohmann::json analyzePacking(const core::Packing& packing, const AnalysisOptions& options = {});

/// Writes the CSV profiles into `dir` (which must exist), each atomically, with a header line and
/// `# key: value` lines from `metadata` (seed, backend, version ...):
/// phi_y.csv, z_y.csv, homogeneity_z.csv, homogeneity_y.csv, orientation_cos.csv,
/// orientation_azimuth.csv.
void writeProfiles(const std::filesystem::path& dir, const Analysis& a, const nlohmann::json& metadata);

}  // namespace confpack::analysis
