#pragma once
// How many cells (slices, grid cells, lattice cells) of a requested side tile a length: the side is
// adjusted so that a whole number of cells tiles it (round(length / side), at least one), but a
// count too large to hold is refused, never clamped. A slice typed far too small (1e-9 d_L) once
// wrapped the count past an int and came out as a single slice the width of the box, a result
// that looked like one at the requested resolution.
#include <string_view>

namespace confpack::analysis {

/// Most cells along one axis [-]. 1e8 cells of a box 10 d_L wide are 1e-7 d_L each, far finer
/// than any feature of a packing, and one profile of them already takes 0.8 GB.
inline constexpr double kMaxCellsAlongAxis = 1e8;

/// round(length / side), at least 1, for length >= 0 and side > 0 [d_L]. Throws
/// std::invalid_argument naming `what` (e.g. "profile: slice") when it exceeds kMaxCellsAlongAxis.
int cellsAlong(double length, double side, std::string_view what);

}  // namespace confpack::analysis
