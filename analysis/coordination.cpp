#include "analysis/coordination.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

#include "analysis/geometric_contacts.hpp"
#include "analysis/grain_volumes.hpp"
#include "analysis/solid_fraction.hpp"
#include "collision/contact_band.hpp"
#include "collision/polyhedron_contact.hpp"

namespace confpack::analysis {

void CoordinationDef::validate() const {
  if (!(forceThreshold >= 0.0) || !std::isfinite(forceThreshold))
    throw std::invalid_argument(fmt::format("coordination: force_threshold must be >= 0 (got {})", forceThreshold));
  if (!(slice > 0.0) || !std::isfinite(slice))
    throw std::invalid_argument(fmt::format("coordination: slice must be positive (got {})", slice));
}

std::vector<CountedContact> forceCarryingContacts(const core::Packing& packing,
                                                  const std::vector<core::Contact>& contacts, bool geometric,
                                                  double forceThreshold) {
  const int n = static_cast<int>(packing.grains.size());
  // Merge by unordered pair; the normal is kept oriented from the smaller index.
  std::map<std::pair<int, int>, CountedContact> merged;
  std::map<std::pair<int, int>, std::vector<double>> pointForces;  // of merged's points, in order
  for (const core::Contact& c : contacts) {
    if (c.a < 0 || c.a >= n || c.b >= n || c.a == c.b || (core::isWall(c.b) && c.b < -3))
      throw std::invalid_argument(fmt::format("contacts: invalid pair ({}, {})", c.a, c.b));
    int a = c.a, b = c.b;
    core::Vec3 normal = c.normal;
    if (!core::isWall(b) && b < a) {
      std::swap(a, b);
      normal = -normal;
    }
    auto [it, fresh] = merged.try_emplace({a, b});
    CountedContact& m = it->second;
    if (fresh) {
      m.a = a;
      m.b = b;
      m.normal = normal;
      if (!core::isWall(b))
        m.branch = packing.box.minimumImage(packing.grains[b].position - packing.grains[a].position);
    }
    m.normalForce += c.normalForce();
    std::vector<double>& forces = pointForces[{a, b}];
    for (const core::ContactPoint& point : c.points) {
      m.points.push_back(point.position);
      forces.push_back(point.normalForce);
    }
  }
  double sum = 0.0;
  int count = 0;
  for (const auto& [key, m] : merged)
    if (!core::isWall(m.b) && m.normalForce > 0.0) {
      sum += m.normalForce;
      ++count;
    }
  const double mean = count > 0 ? sum / count : 0.0;
  std::vector<CountedContact> out;
  for (auto& [key, m] : merged) {
    if (!geometric && !(m.normalForce > forceThreshold * mean && m.normalForce > 0.0)) continue;
    if (!geometric) {
      // A point within the alert distance but open carries no force at rest: not a constraint.
      // (A contact whose force is spread over points each below the threshold keeps them all.)
      const std::vector<double>& forces = pointForces.at(key);
      std::vector<core::Vec3> carrying;
      for (std::size_t i = 0; i < m.points.size(); ++i)
        if (forces[i] > forceThreshold * mean) carrying.push_back(m.points[i]);
      if (!carrying.empty()) m.points = std::move(carrying);
    }
    const core::Grain& ga = packing.grains[m.a];
    if (ga.shape == core::ShapeKind::Pinacoid) {
      const PlacedGrain pa(ga);
      if (core::isWall(m.b)) {
        m.type = collision::classifyPlaneContact(pa.placed, core::BoxDef::wallNormal(static_cast<core::WallId>(m.b)));
      } else if (packing.grains[m.b].shape == core::ShapeKind::Pinacoid) {
        const PlacedGrain pb(packing.grains[m.b], ga.position + m.branch);
        m.type = collision::classifyContact(pa.placed, pb.placed);
      }
    }
    out.push_back(m);
  }
  return out;
}

void checkTypeBand(double band) {
  if (!(band > 0.0 && band <= kMaxTypeBand))
    throw std::invalid_argument(fmt::format(
        "analysis: type_band must be a fraction in (0, {}] of the grain size (got {})", kMaxTypeBand, band));
}

std::vector<CountedContact> bandTypedContacts(const core::Packing& packing, std::vector<CountedContact> counted,
                                              double band) {
  checkTypeBand(band);
  for (CountedContact& c : counted) {
    const core::Grain& ga = packing.grains[c.a];
    if (ga.shape != core::ShapeKind::Pinacoid) continue;
    const PlacedGrain pa(ga);
    if (core::isWall(c.b)) {
      const auto wall = static_cast<core::WallId>(c.b);
      c.type = collision::classifyPlaneContactBand(pa.placed, packing.box.wallPoint(wall),
                                                   core::BoxDef::wallNormal(wall), band * ga.size);
    } else if (const core::Grain& gb = packing.grains[c.b]; gb.shape == core::ShapeKind::Pinacoid) {
      const PlacedGrain pb(gb, ga.position + c.branch);
      c.type = collision::classifyContactBand(pa.placed, pb.placed, band * std::min(ga.size, gb.size));
    }
  }
  return counted;
}

Coordination coordination(const core::Packing& packing, const BulkRegion& region,
                          const std::vector<CountedContact>& counted, bool geometric, const CoordinationDef& def) {
  def.validate();
  Coordination r;
  r.geometric = geometric;
  const int n = static_cast<int>(packing.grains.size());
  std::vector<char> inBulk(n, 0);
  for (int i = 0; i < n; ++i) inBulk[i] = region.contains(packing.grains[i].position.z());
  // Per grain: contacts by type (0, 1, 2), wall contacts.
  std::vector<std::array<int, 3>> byType(n, {0, 0, 0});
  std::vector<int> walls(n, 0), floor(n, 0);
  double forceSum = 0.0;
  int forceCount = 0;
  for (const CountedContact& c : counted) {
    if (core::isWall(c.b)) {
      ++r.wallContacts;
      if (c.b == static_cast<int>(core::WallId::Floor))
        ++floor[c.a];
      else
        ++walls[c.a];
      continue;
    }
    forceSum += c.normalForce;
    ++forceCount;
    const int t = static_cast<int>(c.type);
    ++byType[c.a][t];
    ++byType[c.b][t];
    if (inBulk[c.a] || inBulk[c.b]) ++r.contacts;
  }
  r.meanNormalForce = geometric ? 1.0 : (forceCount > 0 ? forceSum / forceCount : 0.0);

  std::array<double, 3> sumAll{0, 0, 0}, sumActive{0, 0, 0};
  int rattlers = 0, sideWall = 0;
  bool pinacoids = false;
  for (int i = 0; i < n; ++i) {
    if (!inBulk[i]) continue;
    ++r.bulkGrains;
    pinacoids = pinacoids || packing.grains[i].shape == core::ShapeKind::Pinacoid;
    const int zi = byType[i][0] + byType[i][1] + byType[i][2];
    sideWall += walls[i];
    const bool rattler = zi + walls[i] + floor[i] == 0;
    rattlers += rattler;
    for (int t = 0; t < 3; ++t) {
      sumAll[t] += byType[i][t];
      if (!rattler) sumActive[t] += byType[i][t];
    }
  }
  if (r.bulkGrains > 0) {
    const double inv = 1.0 / r.bulkGrains;
    r.zSimple = sumAll[0] * inv;
    r.zDouble = sumAll[1] * inv;
    r.zTriple = sumAll[2] * inv;
    r.z = r.zSimple + r.zDouble + r.zTriple;
    r.rattlerFraction = rattlers * inv;
    r.wallZ = sideWall * inv;
    const int active = r.bulkGrains - rattlers;
    if (active > 0) {
      r.zNonRattler = (sumActive[0] + sumActive[1] + sumActive[2]) / active;
      if (pinacoids) r.hyperstaticity = (sumActive[0] + 2 * sumActive[1] + 3 * sumActive[2]) / active - 12.0;
    }
  }

  // Z(y): distance to the nearer wall (folded) or raw y (biperiodic).
  const core::BoxDef& box = packing.box;
  const double span = box.periodicY ? box.width : 0.5 * box.width;
  const std::vector<double> edges = sliceEdges(span, def.slice, "coordination: Z(y) slice");
  const std::size_t ns = edges.size() - 1;
  const double dy = edges[1] - edges[0];
  CoordinationProfile& p = r.profile;
  p.grains.assign(ns, 0);
  p.z.assign(ns, 0.0);
  p.simple.assign(ns, 0.0);
  p.dbl.assign(ns, 0.0);
  p.triple.assign(ns, 0.0);
  for (std::size_t k = 0; k < ns; ++k) p.y.push_back(0.5 * (edges[k] + edges[k + 1]));
  for (int i = 0; i < n; ++i) {
    if (!inBulk[i]) continue;
    const core::Vec3 x = box.wrap(packing.grains[i].position);
    const double y = box.periodicY ? x.y() : std::min(x.y(), box.width - x.y());
    const auto k =
        static_cast<std::size_t>(std::clamp(static_cast<int>(std::floor(y / dy)), 0, static_cast<int>(ns) - 1));
    ++p.grains[k];
    p.simple[k] += byType[i][0];
    p.dbl[k] += byType[i][1];
    p.triple[k] += byType[i][2];
  }
  for (std::size_t k = 0; k < ns; ++k) {
    if (p.grains[k] == 0) continue;
    p.simple[k] /= p.grains[k];
    p.dbl[k] /= p.grains[k];
    p.triple[k] /= p.grains[k];
    p.z[k] = p.simple[k] + p.dbl[k] + p.triple[k];
  }
  return r;
}

Coordination bulkCoordination(const core::Packing& packing, const BulkRegion& region, const CoordinationDef& def) {
  const bool geometric = !packing.contacts.has_value();
  const std::vector<core::Contact> contacts = geometric ? geometricContacts(packing) : *packing.contacts;
  return coordination(packing, region, forceCarryingContacts(packing, contacts, geometric, def.forceThreshold),
                      geometric, def);
}

}  // namespace confpack::analysis
