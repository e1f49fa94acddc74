#pragma once
// Coordination numbers (docs/model.md, "Coordination number") and the force-carrying contact set
// shared with the fabric.
//
// Force-carrying contacts. Contacts of the same pair reported more than once (several manifolds)
// are merged first (forces summed). A grain-grain contact carries force when its normal force
// exceeds forceThreshold (default 1e-3) times the mean normal force of all grain-grain contacts
// with a positive force; a wall contact likewise against the same mean. Geometric contacts
// (analysis/geometric_contacts.hpp) all carry force.
//
// Contact type. Spheres: Simple. Pinacoid pairs: the shared geometric classifier
// collision::classifyContact(a, b) on the two grains' poses (b at its minimum image), so both
// backends are classified identically, whatever number of points they used. Pinacoid-wall:
// collision::classifyPlaneContact.
// Contact type by a tolerance band B (bandTypedContacts, beside the exact type, never instead):
// collision::classifyContactBand with the band width
//   w = B x min(d_a, d_b)   (a pair),   w = B x d_a   (a wall),
// d the grain's size: every vertex within w of the contact plane touches, and the number of
// distinct positions they touch at gives the type (collision/contact_band.hpp).
//
// Counting (bulk grains: centre in the bulk region). Each force-carrying grain-grain contact adds
// one to each of its grains that is in the bulk, so
//   Z = (sum over bulk grains of their grain-grain contacts) / n_bulk      (= 2 N_c / n inside),
// and Z_s, Z_d, Z_t likewise by type (Z = Z_s + Z_d + Z_t). Side-wall contacts are counted apart
// (wallZ = wall contacts of bulk grains / n_bulk). A rattler is a bulk grain with no
// force-carrying contact at all (grain or wall). The hyperstaticity of frictionless polyhedra,
//   2 h0 / n = Z_s + 2 Z_d + 3 Z_t - 12   (k0 = 0),
// is evaluated over the non-rattlers (a rattler's 6 free motions are mechanisms, k0 != 0), and
// reported for pinacoid packings only.
// Z(y) profile: bulk grains binned by their distance to the nearer wall (folded; raw y when
// biperiodic) in slices of `slice`; per slice, contacts per grain, total and by type.
#include <optional>
#include <vector>

#include "analysis/bulk_region.hpp"

namespace confpack::analysis {

struct CoordinationDef {
  double forceThreshold = 1e-3;  ///< force-carrying: f_n > forceThreshold * mean f_n [-], >= 0
  double slice = 0.25;           ///< slice thickness of the Z(y) profile [d_L], > 0

  void validate() const;  ///< throws std::invalid_argument naming the bad field
};

/// A merged, force-carrying, classified contact.
struct CountedContact {
  int a = 0;  ///< grain index
  int b = 0;  ///< grain index (> a) or wall id
  core::ContactType type = core::ContactType::Simple;
  core::Vec3 normal = core::Vec3::UnitZ();  ///< unit, from a to b
  core::Vec3 branch = core::Vec3::Zero();   ///< minimum-image x_b - x_a (grain pairs) [d_L]
  double normalForce = 0.0;                 ///< summed over merged contacts and points
  /// World positions of the merged contacts' force-carrying points (each point's own force above
  /// the same threshold, or every point if none is; every point of a geometric contact) [d_L].
  std::vector<core::Vec3> points;
};

/// Widest tolerance band accepted, as a fraction of the grain size [-]: half the size already
/// spans most of a pinacoid's thickness (0.71 L across its trapezoids for G = E = L), and any
/// wider band would read every contact as triple.
inline constexpr double kMaxTypeBand = 0.5;

/// Throws std::invalid_argument unless 0 < band <= kMaxTypeBand (finite).
void checkTypeBand(double band);

/// The force-carrying contacts (definition above), merged by pair and classified.
/// `geometric`: all contacts count whatever their force. Throws std::invalid_argument for a grain
/// index out of range.
std::vector<CountedContact> forceCarryingContacts(const core::Packing& packing,
                                                  const std::vector<core::Contact>& contacts, bool geometric,
                                                  double forceThreshold = 1e-3);

/// `counted` with each pinacoid contact's type read by the tolerance band `band` (definition
/// above) instead of the exact rule; sphere contacts stay Simple. Throws std::invalid_argument
/// unless 0 < band <= kMaxTypeBand.
std::vector<CountedContact> bandTypedContacts(const core::Packing& packing, std::vector<CountedContact> counted,
                                              double band);

struct CoordinationProfile {
  std::vector<double> y;                       ///< slice centres [d_L]
  std::vector<int> grains;                     ///< bulk grains per slice
  std::vector<double> z, simple, dbl, triple;  ///< contacts per grain of the slice
};

struct Coordination {
  int bulkGrains = 0;
  int contacts = 0;  ///< force-carrying grain-grain contacts touching the bulk
  double z = 0.0, zSimple = 0.0, zDouble = 0.0, zTriple = 0.0;  ///< per bulk grain
  double zNonRattler = 0.0;                                     ///< Z over non-rattling bulk grains
  double rattlerFraction = 0.0;                                 ///< bulk grains with no force-carrying contact / n_bulk
  double wallZ = 0.0;                                           ///< side-wall contacts of bulk grains / n_bulk
  int wallContacts = 0;                  ///< force-carrying wall contacts of all grains (floor included)
  std::optional<double> hyperstaticity;  ///< Z_s + 2 Z_d + 3 Z_t - 12 over non-rattlers (pinacoids)
  double meanNormalForce = 0.0;          ///< mean f_n of grain-grain contacts with f_n > 0 (1 if geometric)
  bool geometric = false;                ///< contacts were found geometrically
  CoordinationProfile profile;
};

Coordination coordination(const core::Packing& packing, const BulkRegion& region,
                          const std::vector<CountedContact>& counted, bool geometric, const CoordinationDef& def = {});

/// The coordination of `region` as analyze() measures it, for a measurement of its own (a
/// compaction's checks, a settle's before and after): the packing's force-carrying contacts, or
/// its geometric contacts (analysis/geometric_contacts.hpp) when it has none.
Coordination bulkCoordination(const core::Packing& packing, const BulkRegion& region, const CoordinationDef& def = {});

}  // namespace confpack::analysis
