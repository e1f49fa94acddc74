#pragma once
// Hand-built packings with exact answers, shared by the analysis tests.
#include <cmath>
#include <vector>

#include "core/packing.hpp"
#include "tests/support/systems.hpp"

namespace confpack::testing {

/// Simple cubic lattice of touching spheres of diameter d: nx x ny x nz spheres, centres at
/// ((i + 1/2) d, (j + 1/2) d, (k + 1/2) d); box periodic in x and y (lengths nx d, ny d).
inline core::Packing simpleCubic(int nx, int ny, int nz, double d = 1.0) {
  core::Packing p;
  p.box.lengthX = nx * d;
  p.box.width = ny * d;
  p.box.periodicY = true;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        p.grains.push_back(sphere(d, core::Vec3((i + 0.5) * d, (j + 0.5) * d, (k + 0.5) * d)));
      }
  return p;
}

/// Face-centred cubic lattice of touching unit-diameter spheres: cubic cell side a = sqrt(2),
/// 4 spheres per cell at (0,0,0), (a/2,a/2,0), (a/2,0,a/2), (0,a/2,a/2), shifted by
/// (a/4, a/4, a/4 + z0). ncell x ncell x ncz cells, periodic in x and y.
inline core::Packing faceCentredCubic(int ncell, int ncz, double z0 = 0.5) {
  const double a = std::sqrt(2.0);
  core::Packing p;
  p.box.lengthX = ncell * a;
  p.box.width = ncell * a;
  p.box.periodicY = true;
  const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  for (int k = 0; k < ncz; ++k)
    for (int j = 0; j < ncell; ++j)
      for (int i = 0; i < ncell; ++i)
        for (const auto& b : basis) {
          p.grains.push_back(
              sphere(1.0, core::Vec3((i + b[0] + 0.25) * a, (j + b[1] + 0.25) * a, (k + b[2]) * a + z0)));
        }
  return p;
}

/// A vertical column of n touching spheres of diameter d resting on the floor at (x, y).
inline std::vector<core::Grain> column(int n, double x, double y, double d = 1.0) {
  std::vector<core::Grain> out;
  for (int k = 0; k < n; ++k) out.push_back(sphere(d, core::Vec3(x, y, (k + 0.5) * d)));
  return out;
}

}  // namespace confpack::testing
