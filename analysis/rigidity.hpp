#pragma once
// Rigidity of a frictionless sphere packing's contact network (docs/model.md, "Isostaticity").
//
// Each force-carrying contact c (coordination.hpp) constrains the grains' translations along its
// unit normal n_c: the rows of the compatibility matrix G (m contacts x 3N translations) are -n_c
// on grain a and +n_c on grain b (only the grain's part for a wall or the floor); frictionless
// spheres' rotations meet no constraint. With r = rank G,
//   self-stress states  h = m - r   (contact forces in equilibrium with no load: the forces are
//                                    not unique when h > 0),
//   mechanisms          k = 3N - r  (motions that open no contact to first order: the global
//                                    translations along periodic axes, grains gliding on the
//                                    frictionless floor, rattlers).
// A rigid frictionless packing at rest is generically isostatic, h = 0 (Roux, PRE 61, 6802, 2000):
// its forces follow from the geometry alone. Not defined here for pinacoids (contacts of several
// points constrain rotations too; coordination.hpp's hyperstaticity counts them) nor between
// frictional walls (a sticking wall contact constrains three motions).
#include <optional>
#include <string>
#include <vector>

#include "analysis/coordination.hpp"
#include "core/packing.hpp"

namespace confpack::analysis {

struct Rigidity {
  int contacts = 0;          ///< m, force-carrying contacts of all grains, walls and floor included
  int degreesOfFreedom = 0;  ///< 3N
  int rank = 0;              ///< rank of G, from SuiteSparseQR's rank-revealing QR
  int selfStresses = 0;      ///< h = m - rank
  int mechanisms = 0;        ///< k = 3N - rank
};

/// Above this many grains the rigidity is not computed (null): SuiteSparseQR's factor grows faster
/// than the packing (0.3 s at 9,000 grains), and larger packings were not measured.
constexpr int kRigidityMaxGrains = 50000;

/// The rigidity of `packing` over its force-carrying contacts `counted`, or nullopt with
/// `*whyNot` (if given) saying why: a packing with pinacoids, frictional side walls, more than
/// kRigidityMaxGrains grains, or a factorisation that failed.
std::optional<Rigidity> sphereRigidity(const core::Packing& packing, const std::vector<CountedContact>& counted,
                                       std::string* whyNot = nullptr);

}  // namespace confpack::analysis
