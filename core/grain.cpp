#include "core/grain.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace confpack::core {

std::string_view toString(ShapeKind s) {
  return s == ShapeKind::Sphere ? "sphere" : "pinacoid";
}

ShapeKind shapeFromString(std::string_view s) {
  if (s == "sphere") return ShapeKind::Sphere;
  if (s == "pinacoid") return ShapeKind::Pinacoid;
  throw std::invalid_argument(fmt::format("unknown shape '{}' (expected sphere or pinacoid)", s));
}

double Grain::volume() const {
  if (shape == ShapeKind::Sphere) return std::numbers::pi / 6.0 * size * size * size;
  return pinacoidMassProperties(size, params).volume;
}

Mat3 Grain::bodyInertia(double density) const {
  if (shape == ShapeKind::Sphere) {
    const double m = density * volume();
    return Mat3::Identity() * (0.1 * m * size * size);  // (2/5) m r^2
  }
  return pinacoidMassProperties(size, params).inertia(density);
}

double Grain::boundingRadius() const {
  if (shape == ShapeKind::Sphere) return 0.5 * size;
  // The farthest vertex is a rectangle corner or a ridge end.
  const double a = 0.5 * size, g = 0.5 * params.widthRatio * size, e = 0.5 * params.heightRatio * size;
  const double l = pinacoidRidgeHalfLength(size, params);
  return std::max(std::hypot(a, g), std::hypot(l, e));
}

ConvexPolyhedron Grain::polyhedron() const {
  if (shape != ShapeKind::Pinacoid) throw std::logic_error("Grain::polyhedron() called on a sphere");
  return makePinacoid(size, params);
}

std::vector<Vec3> Grain::worldVertices() const {
  std::vector<Vec3> out;
  const Mat3 r = orientation.toRotationMatrix();
  const ConvexPolyhedron poly = polyhedron();  // keep alive: vertices() is a reference into it
  for (const Vec3& v : poly.vertices()) out.push_back(position + r * v);
  return out;
}

double totalVolume(const std::vector<Grain>& grains) {
  double v = 0.0;
  for (const Grain& g : grains) v += g.volume();
  return v;
}

double smallestSize(const std::vector<Grain>& grains) {
  double s = std::numeric_limits<double>::infinity();
  for (const Grain& g : grains) s = std::min(s, g.size);
  return s;
}

}  // namespace confpack::core
