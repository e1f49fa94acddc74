#pragma once
// Contacts found from the geometry alone, for packings without a contact list (docs/model.md,
// "Coordination number": a file without them is analysed with geometric contacts).
//
// Two grains (or a grain and a wall) are in contact when their gap is below
//   tol = absTolerance + relTolerance * (mean size of the two grains)   [d_L]
// (defaults 1e-6 d_L + 1e-6 d: a packing written from a solver touches to rounding, and overlaps
// of any depth count). Spheres: exact centre distances; pinacoids: the exact narrow phase of
// collision/polyhedron_contact.hpp (type, normal, points). Geometric contacts have no force: every
// point carries normalForce = 1 as a marker that the contact is counted (all geometric contacts
// are force-carrying), never a physical value.
#include <vector>

#include "core/packing.hpp"

namespace confpack::analysis {

struct GeometricContactDef {
  double absTolerance = 1e-6;  ///< absolute part of the contact tolerance on the gap [d_L], >= 0
  double relTolerance = 1e-6;  ///< part proportional to the mean grain size of the pair [-], >= 0
  bool walls = true;           ///< include grain-wall contacts (floor, side walls)

  void validate() const;  ///< throws std::invalid_argument naming the bad field
};

/// Contacts (core/contact.hpp conventions: b > a or a wall id, normal from a to b, points near a)
/// of every pair and grain-wall pair within tolerance.
std::vector<core::Contact> geometricContacts(const core::Packing& packing, const GeometricContactDef& def = {});

}  // namespace confpack::analysis
