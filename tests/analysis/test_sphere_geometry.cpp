// Sphere slabs and lenses (analysis/sphere_geometry.hpp) against their closed forms.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/sphere_geometry.hpp"

using namespace confpack;

TEST_CASE("sphere slab volume is the spherical segment", "[analysis][sphere]") {
  const double r = 0.7;
  // Cap of height h: pi h^2 (3r - h)/3.
  const double h = 0.3;
  CHECK(analysis::sphereSlabVolume(r, 2.0, 2.0 + r - h, 10.0) ==
        Approx(std::numbers::pi * h * h * (3 * r - h) / 3.0).epsilon(1e-13));
  CHECK(analysis::sphereSlabVolume(r, 0.0, -1.0, 1.0) == Approx(4.0 / 3.0 * std::numbers::pi * r * r * r));
  CHECK(analysis::sphereSlabVolume(r, 0.0, -1.0, 0.0) == Approx(2.0 / 3.0 * std::numbers::pi * r * r * r));
  CHECK(analysis::sphereSlabVolume(r, 0.0, 0.8, 1.0) == 0.0);
  // Thin slices reproduce the disc area pi (r^2 - z^2).
  const double dz = 1e-4;
  for (double z : {-0.6, -0.2, 0.0, 0.35, 0.69}) {
    const double v = analysis::sphereSlabVolume(r, 0.0, z - dz / 2, z + dz / 2) / dz;
    CHECK(v == Approx(std::numbers::pi * (r * r - z * z)).epsilon(1e-6));
  }
  // A partition of the axis sums to the sphere.
  double sum = 0.0;
  for (double lo = -1.0; lo < 1.0; lo += 0.13) sum += analysis::sphereSlabVolume(r, 0.05, lo, lo + 0.13);
  CHECK(sum == Approx(analysis::sphereVolume(r)).epsilon(1e-13));
}

TEST_CASE("sphere lens volume", "[analysis][sphere]") {
  // Equal spheres: two caps of height h = r - d/2: 2 pi h^2 (3r - h)/3.
  const double r = 0.5, d = 0.8, h = r - d / 2;
  CHECK(analysis::sphereLensVolume(r, r, d) == Approx(2 * std::numbers::pi * h * h * (3 * r - h) / 3).epsilon(1e-13));
  CHECK(analysis::sphereLensVolume(r, r, 1.0) == 0.0);
  CHECK(analysis::sphereLensVolume(0.5, 0.2, 0.1) == Approx(analysis::sphereVolume(0.2)));
  // Unequal radii: caps from the radical plane at x = (d^2 + r1^2 - r2^2) / (2d) from centre 1.
  const double r1 = 0.5, r2 = 0.3, dd = 0.6;
  const double x = (dd * dd + r1 * r1 - r2 * r2) / (2 * dd);
  const double h1 = r1 - x, h2 = r2 - (dd - x);
  const double expected =
      std::numbers::pi * h1 * h1 * (3 * r1 - h1) / 3 + std::numbers::pi * h2 * h2 * (3 * r2 - h2) / 3;
  CHECK(analysis::sphereLensVolume(r1, r2, dd) == Approx(expected).epsilon(1e-13));
}
