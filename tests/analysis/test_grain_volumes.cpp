// Volumes of a grain inside slabs and boxes (analysis/grain_volumes.hpp): partitions and Monte Carlo.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/grain_volumes.hpp"
#include "core/random.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::pinacoid;

TEST_CASE("pinacoid slab volumes: partition sums and Monte Carlo", "[analysis][pinacoid]") {
  core::Rng rng(7, core::StreamId::Test);
  const core::Grain g = pinacoid(1.1, core::Vec3(2.0, 3.0, 4.0), rng.uniformQuaternion());
  std::vector<double> edges;
  for (double z = 3.0; z <= 5.0 + 1e-12; z += 0.1) edges.push_back(z);
  const std::vector<double> v = analysis::grainSlabVolumes(g, 2, edges);
  double sum = 0.0;
  for (double x : v) sum += x;
  CHECK(sum == Approx(g.volume()).epsilon(1e-11));
  // Monte Carlo of the slab 3.9 < z < 4.25 in the bounding cube.
  const analysis::PlacedGrain placed(g);
  const core::Mat3 rt = placed.placed.rotation.transpose();
  const double R = g.boundingRadius();
  const int samples = 200000;
  int hits = 0;
  for (int s = 0; s < samples; ++s) {
    const core::Vec3 x = g.position + core::Vec3(rng.uniform(-R, R), rng.uniform(-R, R), rng.uniform(-R, R));
    if (x.z() > 3.9 && x.z() < 4.25 && placed.shape.contains(rt * (x - g.position))) ++hits;
  }
  const double mc = 8 * R * R * R * hits / samples;
  const double sigma = 8 * R * R * R * std::sqrt(hits * (1.0 - double(hits) / samples)) / samples;
  CHECK(std::abs(analysis::grainSlabVolume(g, 2, 3.9, 4.25) - mc) < 4 * sigma);
}
