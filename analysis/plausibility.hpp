#pragma once
// Plausibility of a packing given for analysis: a file can be well formed (core/packing_io.hpp
// validates every field) and still not be a packing, e.g. grains rescaled by mistake or a contact
// list from another file. Analysing such a file gives numbers that look like results (a solid
// fraction of 3, a coordination of 40), so `confpack analyze` refuses it unless asked not to.
//
// A packing is implausible when
// - a grain is larger than the box: its size exceeds the period L_x, the width W (walls or
//   period) or the height h;
// - the grains' volume exceeds the box region's: phi > 1 in L_x x W x h', with h' the larger of
//   h and the top of the highest grain's bounding sphere (grains are free to stand above h);
// - two grains, or a grain and a wall, overlap deeper than maxOverlapFraction of the smaller
//   grain's size (0.05 d): both backends leave overlaps of 1e-7 d to 1e-3 d at rest, fifty
//   times below, while a mistake in sizes or positions gives overlaps of the order of d;
// - a contact point lies farther than maxContactReach x d beyond the bounding sphere of one of
//   its grains (0.1 d), or farther than that from its wall: a solver's contact points lie on
//   the contact plane between the two surfaces, within its detection distance (0.02 d for
//   Bullet), so such a point belongs to another packing.
// Overlap depths are those of the geometric contacts (analysis/geometric_contacts.hpp: exact for
// spheres, the exact narrow phase for pinacoids).
#include <filesystem>
#include <optional>
#include <string>

#include "core/packing.hpp"

namespace confpack::analysis {

struct PlausibilityDef {
  double maxOverlapFraction = 0.05;  ///< deepest overlap allowed, in sizes of the smaller grain [-]
  double maxContactReach = 0.1;      ///< contact point beyond a grain's bounding sphere, in its size [-]
};

/// Why the packing is implausible (the first reason found; grains by index, lengths in d_L), or
/// nullopt when it is plausible.
std::optional<std::string> implausibility(const core::Packing& packing, const PlausibilityDef& def = {});

/// Refuses a packing read from `file` that mixes spheres and pinacoids (not supported, whatever
/// `allow`), or that is implausible, unless `allow` (`confpack analyze` and
/// `run --from`, and the Python module's analyze): std::invalid_argument
/// "FILE: implausible packing: <why> (--allow-implausible takes it anyway)".
void checkPlausible(const core::Packing& packing, const std::filesystem::path& file, bool allow);

}  // namespace confpack::analysis
