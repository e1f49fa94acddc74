#include "core/population.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "core/pinacoid.hpp"
#include "core/settings_table.hpp"

namespace confpack::core {

const SettingsTable<PopulationDef>& populationTable() {
  using P = PopulationDef;
  static const SettingsTable<P> table = [] {
    SettingsTable<P> t("population");
    t.choice("shape", &P::shape, {{"sphere", ShapeKind::Sphere}, {"pinacoid", ShapeKind::Pinacoid}},
             "grain shape (one per sample)")
        .number("large_size", &P::largeSize, Range::positive(), "d_L", "mean size d_L of the large grains")
        .number("small_size", &P::smallSize, Range::positive(), "d_L", "mean size d_S of the small grains")
        .number("small_fraction", &P::smallFraction, Range::closed(0.0, 100.0), "%",
                "x_S, the small grains' share of the grain volume")
        .number("relative_std", &P::relativeStd, Range::atLeast(0.0), "-",
                "sigma / d of each size distribution (1/30: variance d^2/900)")
        // > 0: the sizes are drawn by rejection inside +-truncation_sigmas, which 0 never accepts.
        .number("truncation_sigmas", &P::truncationSigmas, Range::positive(), "-",
                "the Gaussian of sizes truncated at this many sigma")
        .section("pinacoid", &P::pinacoid, &pinacoidTable, "the pinacoid's shape (shape pinacoid)",
                 [](const P& p) { return p.shape == ShapeKind::Pinacoid; })
        .rule([](const P& p) {
          if (!(p.relativeStd * p.truncationSigmas < 1.0))
            throw std::invalid_argument(fmt::format(
                "population: size spread relative_std x truncation_sigmas = {} x {} must stay below 1 (a grain of "
                "size <= 0 otherwise)",
                p.relativeStd, p.truncationSigmas));
        });
    return t;
  }();
  return table;
}

void PopulationDef::validate() const {
  populationTable().validate(*this);
}

double PopulationDef::maxCircumscribedDiameter() const {
  Grain g;
  g.shape = shape;
  g.size = maxSize();
  g.params = pinacoid;
  return 2.0 * g.boundingRadius();
}

double PopulationDef::meanGrainVolume(double size) const {
  Grain g;
  g.shape = shape;
  g.size = size;
  g.params = pinacoid;
  return g.volume();
}

void to_json(nlohmann::json& j, const PopulationDef& p) {
  j = populationTable().write(p);
}

void from_json(const nlohmann::json& j, PopulationDef& p) {
  p = PopulationDef{};
  populationTable().read(j, p);
}

double drawSize(Rng& rng, double mean, double relativeStd, double truncationSigmas) {
  for (;;) {
    const double z = rng.normal();
    if (std::abs(z) <= truncationSigmas) return mean * (1.0 + relativeStd * z);
  }
}

namespace {

/// A grain of the population with its size drawn around `mean`. The orientation is left to the
/// caller: the two drawing rules below consume the orientation stream differently.
Grain drawGrain(const PopulationDef& def, double mean, Rng& sizes) {
  Grain g;
  g.shape = def.shape;
  g.params = def.pinacoid;
  g.size = drawSize(sizes, mean, def.relativeStd, def.truncationSigmas);
  return g;
}

}  // namespace

std::vector<Grain> drawGrains(const PopulationDef& def, double targetVolume, std::uint64_t seed) {
  def.validate();
  Rng sizes(seed, StreamId::GrainSizes);
  Rng orientations(seed, StreamId::GrainOrientation);
  std::vector<Grain> out;
  auto fill = [&](double mean, double share) {
    double volume = 0.0;
    for (;;) {
      Grain g = drawGrain(def, mean, sizes);
      const double v = g.volume();
      // Stop at the count whose volume is closest to the share.
      if (volume + 0.5 * v > share) break;
      if (def.shape == ShapeKind::Pinacoid) g.orientation = orientations.uniformQuaternion();
      volume += v;
      out.push_back(g);
    }
  };
  fill(def.largeSize, targetVolume * (100.0 - def.smallFraction) / 100.0);
  fill(def.smallSize, targetVolume * def.smallFraction / 100.0);
  return out;
}

std::vector<Grain> drawGrainCount(const PopulationDef& def, std::size_t n, std::uint64_t seed) {
  def.validate();
  // Number share of small grains that makes x_S of the volume with mean grain volumes:
  // n_S/n = (x/v_S) / ((1-x)/v_L + x/v_S).
  const double x = def.smallFraction / 100.0;
  const double vL = def.meanGrainVolume(def.largeSize);
  const double vS = def.meanGrainVolume(def.smallSize);
  const double smallShare = (x / vS) / ((1.0 - x) / vL + x / vS);
  const auto nSmall = static_cast<std::size_t>(std::llround(smallShare * static_cast<double>(n)));
  Rng sizes(seed, StreamId::GrainSizes);
  Rng orientations(seed, StreamId::GrainOrientation);
  std::vector<Grain> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    Grain g = drawGrain(def, i < n - nSmall ? def.largeSize : def.smallSize, sizes);
    if (def.shape == ShapeKind::Pinacoid) g.orientation = orientations.uniformQuaternion();
    out.push_back(g);
  }
  return out;
}

}  // namespace confpack::core
