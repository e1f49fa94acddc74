#pragma once
// Rigidity of a frictionless packing's contact network (docs/model.md, "Isostaticity").
//
// Each force-carrying contact c (coordination.hpp) constrains the relative normal motion of its
// two grains. Spheres: one constraint on the translations, the rows of the compatibility matrix G
// are -n_c on grain a and +n_c on grain b (only the grain's part for a wall or the floor), three
// columns per grain; a frictionless sphere's rotation meets no constraint. Pinacoids: one
// constraint per independent point of the contact, six columns per grain (translation, rotation):
// at a point p the row is -(n, r_a x n) on a and (n, r_b x n) on b, r the lever from the grain's
// centroid. A contact's points give as many independent constraints as their span in the contact
// plane: one (a vertex on a face), two (an edge on a face: its two ends) or three (a face on a
// face), whatever number of points the backend reported, so that a face contact of four points
// counts three, not four.
// With m the constraints, n_dof the grains' degrees of freedom and r = rank G,
//   self-stress states  h = m - r      (contact forces in equilibrium with no load: the forces are
//                                       not unique when h > 0),
//   mechanisms          k = n_dof - r  (motions that open no contact to first order: translations
//                                       along periodic axes, grains gliding on the frictionless
//                                       floor, rattlers).
// A rigid frictionless packing at rest is generically isostatic, h = 0 (Roux, PRE 61, 6802, 2000):
// its forces follow from the geometry alone. Not defined between frictional walls (a sticking wall
// contact constrains three motions).
#include <optional>
#include <string>
#include <vector>

#include "analysis/coordination.hpp"
#include "core/packing.hpp"

namespace confpack::analysis {

struct Rigidity {
  int contacts = 0;          ///< force-carrying contacts of all grains, walls and floor included
  int constraints = 0;       ///< m: one per sphere contact; 1, 2 or 3 per pinacoid contact
  int degreesOfFreedom = 0;  ///< n_dof: 3 per sphere, 6 per pinacoid
  int rank = 0;              ///< rank of G, from SuiteSparseQR's rank-revealing QR
  int grainConstraints = 0;  ///< the constraints between two grains (floor and side walls left out)
  int grainRank = 0;         ///< the rank of their rows of G

  int selfStresses() const { return constraints - rank; }     ///< h = m - rank
  int mechanisms() const { return degreesOfFreedom - rank; }  ///< k = n_dof - rank
  /// h of the grain-grain constraints alone: the self-stresses that the floor and the side walls
  /// take no part in (a grain lying flat on the floor and touching a neighbour's face has one more
  /// constraint than its motions, a degeneracy of the flat boundary rather than of the packing).
  int selfStressesBetweenGrains() const { return grainConstraints - grainRank; }
};

/// Above this many grains the rigidity is not computed (null): SuiteSparseQR's factor grows faster
/// than the packing (0.3 s at 9,000 spheres), and larger packings were not measured.
constexpr int kRigidityMaxGrains = 50000;

/// Points of one pinacoid contact closer than this to the span of the others add no constraint
/// [fraction of the smaller grain's size]: the backends' points of one face contact lie in the
/// contact plane to round-off, and a point off a line by 1e-3 d tilts a grain by 1e-3 radians at most.
constexpr double kConstraintSpan = 1e-3;

/// The rigidity of `packing` over its force-carrying contacts `counted` (with their points for
/// pinacoids), or nullopt with `*whyNot` (if given) saying why: frictional side walls, a pinacoid
/// contact without points, more than kRigidityMaxGrains grains, or a factorisation that failed.
std::optional<Rigidity> contactRigidity(const core::Packing& packing, const std::vector<CountedContact>& counted,
                                        std::string* whyNot = nullptr);

}  // namespace confpack::analysis
