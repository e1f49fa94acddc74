#pragma once
// Geometric deposition (docs/model.md, "Deposition"). Placeholder spheres, each circumscribing the
// largest possible grain, are dropped one at a time at a random (x, y); each falls to the free
// surface of the pile below and is moved to rest on three supports that locally minimise its
// altitude (placeholders with their periodic images, the floor, the side walls), overlapping
// nothing. The real grains, in random order, then replace the placeholders (centre on centre).
#include <cstdint>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "core/box.hpp"
#include "core/population.hpp"

namespace confpack::core {

struct DepositionDef {
  /// Solid fraction expected after compaction [-]. With the target height h it sets the grain
  /// volume to draw: V = phi_expected * L_x * W * h.
  double expectedSolidFraction = 0.60;
  /// Number of grains to deposit; 0 = derive it from the box height and expectedSolidFraction.
  std::size_t grainCount = 0;
  /// Largest number of grains a run may deposit [-]: a guard against a box typed a thousand times
  /// too large, refused before any work instead of failing out of memory. 1e6 is 33 times the
  /// paper's largest pile (30,400 grains), beyond what a run brings to rest in a day here.
  std::size_t maxGrains = 1'000'000;
  /// Most grains a run's box is made for [-]; 0 = no cap. A box whose height and expected solid
  /// fraction would hold more is shortened along x until it holds about this many
  /// (RunConfig::fitLengthToGrainCap), so that no run of a study outgrows the others (a run's
  /// cost grows faster than its grain count). Unlike max_grains, which refuses such a box.
  std::size_t grainCap = 0;

  /// Throws std::invalid_argument naming the bad field.
  void validate() const;
};

template <class T>
class SettingsTable;
/// The keys of DepositionDef (core/settings_table.hpp).
const SettingsTable<DepositionDef>& depositionTable();

void to_json(nlohmann::json& j, const DepositionDef& d);
void from_json(const nlohmann::json& j, DepositionDef& d);

struct Deposit {
  std::vector<Grain> grains;       ///< real grains, centred on the placeholders (substitution done)
  std::vector<Vec3> placeholders;  ///< placeholder centres, same order as grains
  double placeholderDiameter = 0.0;///< [d_L]
  double pileHeight = 0.0;         ///< top of the highest placeholder [d_L]
  double placeholderSolidFraction = 0.0; ///< placeholder volume / (L_x W pileHeight)
  double solidFraction = 0.0;      ///< real grain volume / (L_x W pileHeight)
  double seconds = 0.0;            ///< wall time of the deposition [s]
  /// Placeholders that found no stable seat within the move budget and were left at the lowest
  /// overlap-free position they visited (0 in a healthy deposit).
  std::size_t unsettledCount = 0;
  double meanMoves = 0.0;          ///< mean number of analytic moves (fall/roll) per placeholder
  /// The packing file the grains were read from (`confpack run --from`); empty for a deposit.
  std::string source;
};

/// Called now and then with (placeholders placed, total).
using ProgressFn = std::function<void(std::size_t done, std::size_t total)>;

/// The placeholder pile alone (no grains): `count` equal spheres of diameter `diameter`
/// [d_L] dropped at random (x, y) drawn from `rng`, each settled by analytic falls and rolls.
struct PlaceholderPile {
  std::vector<Vec3> centres;        ///< in deposition order, wrapped into the box [d_L]
  std::size_t unsettledCount = 0;   ///< see Deposit::unsettledCount
  double meanMoves = 0.0;           ///< see Deposit::meanMoves
};

/// Builds the placeholder pile; throws std::invalid_argument if the box cannot hold a placeholder.
PlaceholderPile depositPlaceholders(const BoxDef& box, double diameter, std::size_t count, Rng& rng,
                                    const ProgressFn& progress = {});

/// Drops one placeholder of diameter `diameter` at (x, y) onto the given centres and returns its
/// seat (wrapped into the box); `settled`, if given, tells whether a stable seat was found. For
/// tests and tools: it rebuilds the neighbour grid, O(pile size) per call.
Vec3 dropPlaceholder(const BoxDef& box, double diameter, const std::vector<Vec3>& pile, double x, double y,
                     bool* settled = nullptr);

/// Deposits a pile for this box and population. Reproducible from `seed` bit for bit.
Deposit deposit(const BoxDef& box, const PopulationDef& population, const DepositionDef& def,
                std::uint64_t seed, const ProgressFn& progress = {});

}  // namespace confpack::core
