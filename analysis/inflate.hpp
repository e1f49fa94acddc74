#pragma once
// The inflated reading of a packing (docs/model.md, "Two readings of a packing"): every grain
// scaled by S about its centroid before the analysis, as published analyses close the gaps a
// solver leaves between touching grains.
//
// A sphere's diameter d becomes S d; a pinacoid's length L becomes S L, its shape ratios G/L,
// E/L and alpha kept, so that every vertex x_b of its body frame (centroid at the origin) becomes
// S x_b and its volume S^3 V. Positions and orientations are kept. The contact list is dropped:
// the inflated grains touch where they overlap, which the analysis finds geometrically
// (analysis/geometric_contacts.hpp), whatever forces the packing carried.
#include "core/packing.hpp"

namespace confpack::analysis {

/// Largest inflation accepted [-]. A simple cubic lattice inflated by 1.5 already overlaps its
/// nearest neighbours by half a diameter and reaches its second ones (sqrt 2 = 1.41 apart): beyond
/// it the reading no longer describes the packing's contacts.
inline constexpr double kMaxInflation = 1.5;

/// Throws std::invalid_argument unless 1 <= scale <= kMaxInflation (finite).
void checkInflation(double scale);

/// A copy of `packing` with every grain scaled by `scale` about its centroid and no contact list
/// (definition above). Throws std::invalid_argument for a scale checkInflation refuses.
core::Packing inflate(const core::Packing& packing, double scale);

}  // namespace confpack::analysis
