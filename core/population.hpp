#pragma once
// Grain populations (docs/model.md, "Mixtures"): one or two sizes (large d_L, small d_S = d_L/2) of
// one shape, each size drawn from a Gaussian of standard deviation d/30 truncated at 3 sigma, mixed
// so that small grains make x_S percent of the solid volume.
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "core/grain.hpp"
#include "core/random.hpp"

namespace confpack::core {

struct PopulationDef {
  ShapeKind shape = ShapeKind::Sphere;
  double largeSize = 1.0;           ///< mean size of the large population d_L [d_L]
  double smallSize = 0.5;           ///< mean size of the small population d_S [d_L]
  double smallFraction = 0.0;       ///< x_S, volume percentage of small grains, in [0, 100]
  double relativeStd = 1.0 / 30.0;  ///< sigma / d (variance d^2/900) [-]
  double truncationSigmas = 3.0;    ///< Gaussian truncated at this many sigma [-]
  PinacoidParams pinacoid{};        ///< shape parameters when shape == Pinacoid

  void validate() const;  ///< throws std::invalid_argument naming the bad field
  /// Largest size any grain can have (mean + truncation of the large population).
  double maxSize() const { return largeSize * (1.0 + truncationSigmas * relativeStd); }
  /// Diameter of the sphere circumscribing the largest possible grain (the placeholder size).
  double maxCircumscribedDiameter() const;
  /// Mean volume of one grain of mean size `size`.
  double meanGrainVolume(double size) const;
};

template <class T>
class SettingsTable;
/// The keys of PopulationDef (core/settings_table.hpp): JSON reader, writer and validation.
const SettingsTable<PopulationDef>& populationTable();
void to_json(nlohmann::json& j, const PopulationDef& p);
void from_json(const nlohmann::json& j, PopulationDef& p);

/// One truncated-Gaussian size draw around `mean` (rejection, so the shape inside the cut is
/// exactly Gaussian).
double drawSize(Rng& rng, double mean, double relativeStd, double truncationSigmas);

/// Draws grains (sizes, and orientations for pinacoids) whose total volume approaches
/// `targetVolume`, small grains making smallFraction % of it. Each population stops at the count
/// whose volume is closest to its share. Positions are left at zero; the order is large grains
/// then small ones (deposition shuffles them).
std::vector<Grain> drawGrains(const PopulationDef& def, double targetVolume, std::uint64_t seed);

/// Draws exactly n grains: the small population's number share is the one that gives x_S of the
/// volume with mean grain volumes; large grains first, then small ones (same streams as drawGrains).
std::vector<Grain> drawGrainCount(const PopulationDef& def, std::size_t n, std::uint64_t seed);

}  // namespace confpack::core
