#pragma once
// Geometric deposition (docs/model.md, "Deposition"). Placeholder spheres, each circumscribing the
// largest possible grain, are dropped one at a time at a random (x, y); each falls to the free
// surface of the pile below and is moved to rest on three supports that locally minimise its
// altitude (placeholders with their periodic images, the floor, the side walls), overlapping
// nothing. The real grains, in random order, then replace the placeholders (centre on centre).
#include <cstdint>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/box.hpp"
#include "core/contact.hpp"
#include "core/population.hpp"
#include "core/random.hpp"
#include "core/run_config.hpp"

namespace confpack::compaction {

struct Deposit {
  std::vector<core::Grain> grains;        ///< real grains, centred on the placeholders (substitution done)
  std::vector<core::Vec3> placeholders;   ///< placeholder centres, same order as grains
  double placeholderDiameter = 0.0;       ///< [d_L]
  double pileHeight = 0.0;                ///< top of the highest placeholder [d_L]
  double placeholderSolidFraction = 0.0;  ///< placeholder volume / (L_x W pileHeight)
  double solidFraction = 0.0;             ///< real grain volume / (L_x W pileHeight)
  double seconds = 0.0;                   ///< wall time of the deposition [s]
  /// Placeholders that found no stable seat within the move budget and were left at the lowest
  /// overlap-free position they visited (0 in a healthy deposit).
  std::size_t unsettledCount = 0;
  double meanMoves = 0.0;  ///< mean number of analytic moves (fall/roll) per placeholder
  /// The packing file the grains were read from (`confpack run --from`); empty for a deposit.
  std::string source;
  /// That packing's contacts with their forces, as the backend that made it left them: what the
  /// settle record measures "before" (docs/model.md, "Settling a pile from another backend").
  /// None for a deposit.
  std::optional<std::vector<core::Contact>> contacts;
};

/// Called now and then with (placeholders placed, total).
using ProgressFn = std::function<void(std::size_t done, std::size_t total)>;

/// The placeholder pile alone (no grains): `count` equal spheres of diameter `diameter`
/// [d_L] dropped at random (x, y) drawn from `rng`, each settled by analytic falls and rolls.
struct PlaceholderPile {
  std::vector<core::Vec3> centres;  ///< in deposition order, wrapped into the box [d_L]
  std::size_t unsettledCount = 0;   ///< see Deposit::unsettledCount
  double meanMoves = 0.0;           ///< see Deposit::meanMoves
};

/// Builds the placeholder pile; throws std::invalid_argument if the box cannot hold a placeholder.
PlaceholderPile depositPlaceholders(const core::BoxDef& box, double diameter, std::size_t count, core::Rng& rng,
                                    const ProgressFn& progress = {});

/// Drops one placeholder of diameter `diameter` at (x, y) onto the given centres and returns its
/// seat (wrapped into the box); `settled`, if given, tells whether a stable seat was found. For
/// tests and tools: it rebuilds the neighbour grid, O(pile size) per call.
core::Vec3 dropPlaceholder(const core::BoxDef& box, double diameter, const std::vector<core::Vec3>& pile, double x,
                           double y, bool* settled = nullptr);

/// Deposits a pile for this box and population. Reproducible from `seed` bit for bit.
Deposit deposit(const core::BoxDef& box, const core::PopulationDef& population, const core::DepositionDef& def,
                std::uint64_t seed, const ProgressFn& progress = {});

}  // namespace confpack::compaction
