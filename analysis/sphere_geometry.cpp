#include "analysis/sphere_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace confpack::analysis {

namespace {
// Volume of the part of a sphere of radius r below the plane at signed height u from its centre.
double volumeBelow(double r, double u) {
  u = std::clamp(u, -r, r);
  return std::numbers::pi * (r * r * u - u * u * u / 3.0 + 2.0 * r * r * r / 3.0);
}
}  // namespace

double sphereVolume(double radius) {
  return 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
}

double sphereSlabVolume(double radius, double centre, double lo, double hi) {
  if (!(hi > lo) || radius <= 0.0) return 0.0;
  // Whole sphere inside: return the exact volume rather than a difference of two large terms.
  if (lo <= centre - radius && hi >= centre + radius) return sphereVolume(radius);
  return std::max(0.0, volumeBelow(radius, hi - centre) - volumeBelow(radius, lo - centre));
}

double sphereLensVolume(double r1, double r2, double distance) {
  const double d = std::abs(distance);
  if (d >= r1 + r2) return 0.0;
  if (d <= std::abs(r1 - r2)) return sphereVolume(std::min(r1, r2));
  const double h = r1 + r2 - d;
  return std::numbers::pi * h * h * (d * d + 2.0 * d * (r1 + r2) - 3.0 * (r1 - r2) * (r1 - r2)) / (12.0 * d);
}

}  // namespace confpack::analysis
