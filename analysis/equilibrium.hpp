#pragma once
// Static equilibrium test (docs/model.md, "Equilibrium") and the contact stress tensor it is
// scaled by.
//
// Per grain i (size d_i, mass m_i = rho V_i):
//   sum F_i = m_i g + sum of the contact forces on i (normal and, at walls, friction),
//   sum M_i = sum over contact points p of (x_p - x_i) x f_p   (moments about the centroid),
//   E_k,i   = m_i |v_i|^2 / 2 + w_i . (R I_body R^T) w_i / 2,
// and the packing is at equilibrium when, for every grain, rattlers included (they must be at
// rest, gravity unbalanced makes them fail),
//   |sum F| < forceRatio d^2 P,  |sum M| < momentRatio d^3 P,  E_k < kineticRatio d^3 P.
//
// P is the mean pressure tr(sigma)/3 of the contact stress (Love-Weber), compression positive:
//   sigma = -(1/V) sum_{grains i in the bulk} sum_{points p of i} (x_p - x_i) (x) f_p^i,
// V the bulk-slab volume and f_p^i the force on grain i at point p. Summing over grains (rather
// than over contacts) is the choice documented here: a contact between two bulk grains then
// contributes exactly (1/V) l (x) f with l = x_b - x_a the minimum-image branch vector and f the
// force on b (the model's sigma = (1/V) sum l (x) f); a contact with one grain outside the slab
// contributes its in-bulk grain's half; a wall contact contributes with the branch from the
// centre to the contact point. Only the symmetric part is kept.
// A pile too low to have a bulk region (tests, small columns) falls back to all grains and the
// volume L_x W h_free: the scale is then the pile's own mean pressure.
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "analysis/bulk_region.hpp"
#include "core/backend.hpp"
#include "core/packing.hpp"

namespace confpack::analysis {

struct EquilibriumReport {
  bool reached = false;           ///< all three ratios below their thresholds for every grain
  double maxForceRatio = 0.0;     ///< max_i |sum F_i| / (d_i^2 P) [-]
  double maxMomentRatio = 0.0;    ///< max_i |sum M_i| / (d_i^3 P) [-]
  double maxKineticRatio = 0.0;   ///< max_i E_k,i / (d_i^3 P) [-]
  double meanKineticRatio = 0.0;  ///< the mean over grains of E_k,i / (d_i^3 P) [-]
  /// The same mean without the spin of spheres, the energy of the motion that can still change the
  /// packing [-]: a sphere's spin leaves its boundary in place, and once a sphere spun by wall
  /// friction leaves the wall, its frictionless contacts never stop it.
  double meanSettlingKineticRatio = 0.0;
  double pressure = 0.0;         ///< P = tr(sigma)/3 [rho g d_L]
  int worstGrain = -1;           ///< grain with the largest force ratio (-1: no grains)
  bool pressureFromBulk = true;  ///< false: the fallback over the whole pile was used
};

/// Contact stress tensor (definition above) of the grains whose centre is in `region` (all grains
/// and the volume L_x W freeSurface when the region holds none) [rho g d_L]. Requires contacts.
core::Mat3 contactStress(const core::Packing& packingWithContacts, const BulkRegion& region, bool* usedBulk = nullptr);

/// Equilibrium report (docs/model.md, "Equilibrium"). `states` gives velocities (empty = all at
/// rest); positions and orientations are read from packing.grains. Throws std::invalid_argument if
/// the packing has no contact list or `states` has the wrong size. When P <= 0 (no forces at all)
/// the ratios are +infinity and `reached` is false.
EquilibriumReport equilibrium(const core::Packing& packingWithContacts, const std::vector<core::BodyState>& states,
                              const core::Vec3& gravity, double density, double forceRatio = 1e-4,
                              double momentRatio = 1e-4, double kineticRatio = 1e-8,
                              const BulkRegionDef& regionDef = {});

/// {"reached", "max_force_ratio", "max_moment_ratio", "max_kinetic_ratio", "pressure",
///  "worst_grain", "pressure_from_bulk"}; infinite ratios are written as null.
void to_json(nlohmann::json& j, const EquilibriumReport& r);

}  // namespace confpack::analysis
