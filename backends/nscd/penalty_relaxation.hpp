#pragma once
// The penalty relaxation of the quasi-static protocol (docs/model.md, "Quasi-static compaction").
//
// Static equilibrium of frictionless rigid grains is a minimum of the potential energy
// U(q) = -F_ext.q under non-penetration. This part approaches it through the exterior penalty
//     U_k(q) = -F_ext.q + k/2 sum_points max(0, -gap_p(q))^2,
// whose minimiser tends to the constrained one as k grows, minimised by FIRE (Bitzek et al., PRL
// 97, 170201, 2006; the semi-implicit Euler form of Guenole et al., Comput. Mater. Sci. 175,
// 109584, 2020) with the true gaps of the narrow phase at every iteration: unlike the finisher's
// steps, its moves are not bounded by the linearised gaps, and an iteration costs one force
// evaluation instead of a contact solve. k climbs a ladder kappa = 1e3, 1e4, ... up to
// `finalStiffness` in units of m g / d of the smallest grain, so that each rung starts near its
// minimum and the deepest overlap ends near (load of a contact) / k. The rigid finisher then
// removes those overlaps and proves equilibrium with the contact solver's own forces.
//
// Side-wall friction: each (grain, side wall) contact carries a tangential spring of the same
// stiffness, its force capped at mu_w times the normal force (the spring slides at the cap), so
// that a grain held by friction during the fall stays held.
#include <vector>

#include "backends/nscd/broad_phase.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "core/backend.hpp"
#include "core/box.hpp"
#include "core/types.hpp"

namespace confpack::nscd {

/// Mass and shape data of the grains, fixed for a backend's life.
struct RelaxationBodies {
  const std::vector<double>* invMass = nullptr;
  const std::vector<core::Mat3>* invInertiaBody = nullptr;
  const std::vector<double>* radius = nullptr;  ///< bounding radius [d_L]
  const std::vector<double>* reach = nullptr;   ///< broad-phase reach (bounding radius + alert) [d_L]
};

class PenaltyRelaxation {
 public:
  /// `finalStiffness` is the last rung's kappa [-]; `forceTolerance` the largest |net force| /
  /// (m g) of a grain at which the last rung stops [-]; `maxIterations` bounds all rungs together.
  PenaltyRelaxation(double finalStiffness, double forceTolerance, long maxIterations);

  /// Relaxes `positions` and `orientations` (positions left unwrapped; the caller wraps them).
  /// Polls core::stopSignal() and throws core::Interrupted.
  core::RelaxationOutcome run(const core::BoxDef& box, const core::Vec3& gravity, const RelaxationBodies& bodies,
                        NarrowPhase& narrow, BroadPhase& broad, int threads, std::vector<core::Vec3>& positions,
                        std::vector<core::Quat>& orientations);

 private:
  double finalStiffness_, forceTolerance_;
  long maxIterations_;
};

}  // namespace confpack::nscd
