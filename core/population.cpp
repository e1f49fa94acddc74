#include "core/population.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace confpack::core {

void PopulationDef::validate() const {
  if (!(largeSize > 0.0) || !(smallSize > 0.0))
    throw std::invalid_argument(fmt::format("population: sizes must be positive (large {}, small {})", largeSize, smallSize));
  if (!(smallFraction >= 0.0 && smallFraction <= 100.0))
    throw std::invalid_argument(fmt::format("population: small fraction must be in [0, 100] % (got {})", smallFraction));
  if (!(relativeStd >= 0.0 && relativeStd * truncationSigmas < 1.0))
    throw std::invalid_argument(fmt::format("population: size spread {} x {} sigma must stay below 1", relativeStd, truncationSigmas));
  if (shape == ShapeKind::Pinacoid) pinacoid.validate();
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
  j = {{"shape", std::string(toString(p.shape))},
       {"large_size", p.largeSize},
       {"small_size", p.smallSize},
       {"small_fraction", p.smallFraction},
       {"relative_std", p.relativeStd},
       {"truncation_sigmas", p.truncationSigmas},
       {"pinacoid", p.pinacoid}};
}

void from_json(const nlohmann::json& j, PopulationDef& p) {
  PopulationDef d;
  p.shape = shapeFromString(j.value("shape", std::string("sphere")));
  p.largeSize = j.value("large_size", d.largeSize);
  p.smallSize = j.value("small_size", d.smallSize);
  p.smallFraction = j.value("small_fraction", d.smallFraction);
  p.relativeStd = j.value("relative_std", d.relativeStd);
  p.truncationSigmas = j.value("truncation_sigmas", d.truncationSigmas);
  p.pinacoid = j.value("pinacoid", d.pinacoid);
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
