#include "analysis/plausibility.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "analysis/geometric_contacts.hpp"

namespace confpack::analysis {

namespace {

using Reason = std::optional<std::string>;

std::string partnerName(int b) {
  switch (static_cast<core::WallId>(b)) {
    case core::WallId::Floor:
      return "the floor";
    case core::WallId::SideLow:
      return "the side wall y = 0";
    case core::WallId::SideHigh:
      return "the side wall y = W";
  }
  return fmt::format("grain {}", b);
}

Reason grainLargerThanBox(const core::Packing& p) {
  const core::BoxDef& box = p.box;
  const std::pair<double, const char*> lengths[] = {
      {box.lengthX, "period L_x"}, {box.width, box.periodicY ? "period along y" : "width W"}, {box.height, "height h"}};
  for (std::size_t i = 0; i < p.grains.size(); ++i)
    for (const auto& [length, name] : lengths)
      if (p.grains[i].size > length)
        return fmt::format("grain {} (size {:g}) is larger than the box's {} ({:g})", i, p.grains[i].size, name,
                           length);
  return std::nullopt;
}

Reason solidFractionAboveOne(const core::Packing& p) {
  double top = p.box.height;
  for (const core::Grain& g : p.grains) top = std::max(top, g.position.z() + g.boundingRadius());
  const double region = p.box.lengthX * p.box.width * top;
  const double solid = core::totalVolume(p.grains);
  if (solid <= region) return std::nullopt;
  return fmt::format("the grains' volume {:.6g} exceeds the box's {:.6g} (L_x x W x {:.6g}): phi = {:.4g} > 1", solid,
                     region, top, solid / region);
}

Reason contactPointAstray(const core::Packing& p, const PlausibilityDef& def) {
  if (!p.contacts) return std::nullopt;
  const core::BoxDef& box = p.box;
  for (std::size_t k = 0; k < p.contacts->size(); ++k) {
    const core::Contact& c = (*p.contacts)[k];
    for (const core::ContactPoint& point : c.points) {
      for (const int id : {c.a, c.b}) {
        if (core::isWall(id)) continue;
        const core::Grain& g = p.grains[id];
        const double reach = box.minimumImage(point.position - g.position).norm() - g.boundingRadius();
        if (reach > def.maxContactReach * g.size)
          return fmt::format(
              "contacts[{}] has a point {:.4g} beyond the bounding sphere of grain {} (more than {:g} "
              "of its size {:g})",
              k, reach, id, def.maxContactReach, g.size);
      }
      if (!core::isWall(c.b)) continue;
      const auto wall = static_cast<core::WallId>(c.b);
      const double distance = std::abs(core::BoxDef::wallNormal(wall).dot(point.position - box.wallPoint(wall)));
      const double size = p.grains[c.a].size;
      if (distance > def.maxContactReach * size)
        return fmt::format("contacts[{}] has a point {:.4g} away from {} (more than {:g} of grain {}'s size {:g})", k,
                           distance, partnerName(c.b), def.maxContactReach, c.a, size);
    }
  }
  return std::nullopt;
}

Reason deepOverlap(const core::Packing& p, const PlausibilityDef& def) {
  // Zero tolerance: exactly the touching and overlapping pairs, grain-wall ones included, with
  // their gaps.
  for (const core::Contact& c : geometricContacts(p, GeometricContactDef{0.0, 0.0, true})) {
    double depth = 0.0;
    for (const core::ContactPoint& point : c.points) depth = std::max(depth, -point.gap);
    const double smaller = core::isWall(c.b) ? p.grains[c.a].size : std::min(p.grains[c.a].size, p.grains[c.b].size);
    if (depth > def.maxOverlapFraction * smaller)
      return fmt::format("grain {} and {} overlap by {:.4g} (more than {:g} of the smaller size {:g})", c.a,
                         partnerName(c.b), depth, def.maxOverlapFraction, smaller);
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> implausibility(const core::Packing& packing, const PlausibilityDef& def) {
  // Cheapest first; the overlaps last, as their neighbour search assumes grains smaller than the
  // box.
  if (Reason r = grainLargerThanBox(packing)) return r;
  if (Reason r = solidFractionAboveOne(packing)) return r;
  if (Reason r = contactPointAstray(packing, def)) return r;
  return deepOverlap(packing, def);
}

void checkPlausible(const core::Packing& packing, const std::filesystem::path& file, bool allow) {
  // Spheres and pinacoids are never in one packing (README, "Known limitations"): neither the
  // backends nor the analysis has sphere-pinacoid contacts. The file format can hold both.
  for (std::size_t i = 0; i < packing.grains.size(); ++i)
    if (packing.grains[i].shape != packing.grains.front().shape)
      throw std::invalid_argument(fmt::format(
          "{}: grains[{}].shape: {}, but grains[0] is a {}: a packing mixing spheres and pinacoids is "
          "not supported",
          file.string(), i, core::toString(packing.grains[i].shape), core::toString(packing.grains.front().shape)));
  if (allow) return;
  if (const auto why = implausibility(packing))
    throw std::invalid_argument(
        fmt::format("{}: implausible packing: {} (--allow-implausible takes it anyway)", file.string(), *why));
}

}  // namespace confpack::analysis
