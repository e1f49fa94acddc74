#pragma once
// Reproducible random streams (after HOOMD's RNGIdentifiers.h).
// Every stream is derived from (user seed, stream id, run index) by SplitMix64 mixing and drives a
// xoshiro256** generator. Raw 64-bit draws are mapped to doubles here, not by <random>'s
// distributions, whose output differs between standard libraries.
#include <array>
#include <cstdint>

#include "core/types.hpp"

namespace confpack::core {

/// Every random stream of the project, in one place. Never reorder: values are part of the
/// reproducibility contract (a packing is a function of its seed).
enum class StreamId : std::uint32_t {
  DepositionXY = 1,      ///< drop positions of placeholders
  GrainSizes = 2,        ///< Gaussian size draws
  GrainOrder = 3,        ///< order in which grains replace placeholders
  GrainOrientation = 4,  ///< random orientations of pinacoids
  Test = 1000,           ///< tests only
};

class Rng {
 public:
  Rng(std::uint64_t seed, StreamId stream, std::uint64_t runIndex = 0);

  std::uint64_t next();
  /// Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform in [a, b).
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  /// Uniform integer in [0, n).
  std::uint64_t below(std::uint64_t n);
  /// Standard normal deviate (Box-Muller, both values used).
  double normal();
  /// Orientation uniform on SO(3): a normalised 4-D Gaussian quaternion.
  Quat uniformQuaternion();

 private:
  std::array<std::uint64_t, 4> s_{};
  double spareNormal_ = 0.0;
  bool hasSpare_ = false;
};

}  // namespace confpack::core
