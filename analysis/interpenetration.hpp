#pragma once
// Interpenetration of the grains in the bulk region (docs/model.md, "Interpenetration"), in %
// of the grain volume.
//
// I = (sum over overlapping pairs of the overlap volume lying in the bulk slab) /
//     (grain volume in the bulk slab, as in solid_fraction) x 100.
// Spheres: exact lens volumes (two caps); a lens is counted wholly when its centre (on the line
// of centres, in the radical plane) lies in the slab (lenses are ~1e-3 d_L thick, so the error at
// the two horizontal planes is negligible and unbiased). Pinacoids: the exact intersection
// polytope of the pair clipped by the two slab planes.
//
// Lattice bounds (pinacoids). The slab is tiled by cells of side close to `cell`
// (default d_L/20; each axis uses L / round(L / cell) so that the cells tile the period, the
// width and the slab height exactly). In a cell c with grain volumes v_i = |G_i ∩ c| (exact
// box clipping), V_sol = sum v_i, and covered volume U = |∪ G_i ∩ c| <= V_cell, the overlap in
// the cell O_c = sum_{i<j} |G_i ∩ G_j ∩ c| satisfies
//   lower: O_c >= V_sol - U >= V_sol - V_cell   (Bonferroni: sum v_i - |∪| <= sum of pairs),
//   upper: O_c <= sum_{i<j} min(v_i, v_j)        (each pairwise overlap lies in both grains).
// For two grains in a cell the upper bound is <= V_sol / 2, and a cell with V_sol/2 = V_cell
// (two grains each filling it) has O_c = V_cell exactly: the two statements of docs/model.md. I_min
// and I_max sum these bounds over the cells. Only cells inside the bounding box of an overlapping
// pair's intersection can hold overlap, so only the cells crossed by an intersection polytope are
// visited (found by cutting the polytope into x slabs, y columns and z cells; other cells
// contribute 0 to both bounds); a cell's V_sol still counts every grain that reaches it (the pair's
// grains and their neighbours). Both bounds are rigorous, so I_min <= I <= I_max, and their gap is
// the cells cut by the overlap boundary: it shrinks linearly with the cell side.
// Spheres have no exact sphere-box volume here, so their lattice bounds are absent (null).
#include <cstddef>
#include <optional>
#include <string>

#include "analysis/bulk_region.hpp"

namespace confpack::analysis {

struct InterpenetrationDef {
  double cell = 0.05;                 ///< lattice cell side [d_L] (d_L/20), > 0
  bool lattice = true;                ///< compute the lattice bounds (pinacoids only)
  std::size_t maxCells = 20'000'000;  ///< cost cap: skip the bounds (null) beyond this many (cell, pair) entries

  void validate() const;  ///< throws std::invalid_argument naming the bad field
};

struct Interpenetration {
  double exactPercent = 0.0;                ///< 100 overlap / grain volume in the slab [%]
  std::optional<double> latticeMinPercent;  ///< lattice lower bound [%] (pinacoids)
  std::optional<double> latticeMaxPercent;  ///< lattice upper bound [%] (pinacoids)
  double overlapVolume = 0.0;               ///< overlap in the slab [d_L^3]
  double grainVolume = 0.0;                 ///< grain volume in the slab [d_L^3]
  int overlappingPairs = 0;                 ///< pairs with a positive overlap counted in the slab
  double maxSphereDepth = 0.0;              ///< largest r_i + r_j - |x_ij| over sphere pairs [d_L]
  int latticeCells = 0;                     ///< cells visited by the lattice method
  std::string latticeSkipped;               ///< why the bounds are absent for pinacoids (cost cap)
};

Interpenetration interpenetration(const core::Packing& packing, const BulkRegion& region,
                                  const InterpenetrationDef& def = {});

}  // namespace confpack::analysis
