#include "analysis/geometric_contacts.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "analysis/grain_volumes.hpp"
#include "analysis/neighbour_pairs.hpp"
#include "collision/polyhedron_contact.hpp"
#include "core/interrupt.hpp"

namespace confpack::analysis {

void GeometricContactDef::validate() const {
  if (!(absTolerance >= 0.0) || !std::isfinite(absTolerance))
    throw std::invalid_argument(fmt::format("geometric contacts: abs_tolerance must be >= 0 (got {})", absTolerance));
  if (!(relTolerance >= 0.0) || !std::isfinite(relTolerance))
    throw std::invalid_argument(fmt::format("geometric contacts: rel_tolerance must be >= 0 (got {})", relTolerance));
}

namespace {

core::Contact fromPolyhedronContact(int a, int b, const collision::PolyhedronContact& pc) {
  core::Contact c;
  c.a = a;
  c.b = b;
  c.type = pc.type;
  c.normal = pc.normal;
  for (std::size_t k = 0; k < pc.points.size(); ++k)
    c.points.push_back({pc.points[k], 1.0, core::Vec3::Zero(), k < pc.pointGaps.size() ? pc.pointGaps[k] : pc.gap});
  return c;
}

}  // namespace

std::vector<core::Contact> geometricContacts(const core::Packing& packing, const GeometricContactDef& def) {
  def.validate();
  std::vector<core::Contact> out;
  const auto& grains = packing.grains;
  auto tolerance = [&](double sizeA, double sizeB) {
    return def.absTolerance + def.relTolerance * 0.5 * (sizeA + sizeB);
  };
  const double maxTol = def.absTolerance + def.relTolerance * 2.0;  // generous pre-filter
  const std::vector<NeighbourPair> pairs = neighbourPairs(packing, maxTol + 1e-9);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    core::stopIfRequested(
        [&] { return fmt::format("while finding the geometric contacts (pair {} of {})", k + 1, pairs.size()); });
    const NeighbourPair& np = pairs[k];
    const core::Grain& a = grains[np.i];
    const core::Grain& b = grains[np.j];
    const double tol = tolerance(a.size, b.size);
    if (a.shape != b.shape)
      throw std::invalid_argument("geometric contacts: mixed sphere-pinacoid packings are not supported");
    if (a.shape == core::ShapeKind::Sphere) {
      const double d = np.separation.norm();
      const double gap = d - 0.5 * (a.size + b.size);
      if (gap > tol) continue;
      core::Contact c;
      c.a = np.i;
      c.b = np.j;
      // Coincident centres (d = 0) have no line of centres, but they are the deepest overlap there
      // is (gap = -(r_a + r_b)): any unit normal will do, and dropping the pair would pass two
      // grains in one place as no contact at all (the plausibility check reads these depths).
      c.normal = d > 0.0 ? core::Vec3(np.separation / d) : core::Vec3::UnitZ();
      // Midway between the two surfaces.
      const core::Vec3 point = a.position + c.normal * (0.5 * a.size + 0.5 * gap);
      c.points.push_back({point, 1.0, core::Vec3::Zero(), gap});
      out.push_back(c);
    } else {
      const PlacedGrain pa(a), pb(b, a.position + np.separation);
      if (auto pc = collision::collidePolyhedra(pa.placed, pb.placed, tol))
        out.push_back(fromPolyhedronContact(np.i, np.j, *pc));
    }
  }
  if (!def.walls) return out;
  const core::BoxDef& box = packing.box;
  std::vector<core::WallId> walls{core::WallId::Floor};
  if (!box.periodicY) {
    walls.push_back(core::WallId::SideLow);
    walls.push_back(core::WallId::SideHigh);
  }
  for (int i = 0; i < static_cast<int>(grains.size()); ++i) {
    const core::Grain& g = grains[i];
    const double tol = tolerance(g.size, g.size);
    for (core::WallId w : walls) {
      const core::Vec3 inward = core::BoxDef::wallNormal(w);
      const core::Vec3 point = box.wallPoint(w);
      const double centreDistance = inward.dot(g.position - point);
      if (centreDistance - g.boundingRadius() > tol) continue;
      if (g.shape == core::ShapeKind::Sphere) {
        const double gap = centreDistance - 0.5 * g.size;
        if (gap > tol) continue;
        core::Contact c;
        c.a = i;
        c.b = static_cast<int>(w);
        c.normal = -inward;
        c.points.push_back({g.position - inward * (0.5 * g.size + 0.5 * gap), 1.0, core::Vec3::Zero(), gap});
        out.push_back(c);
      } else {
        const PlacedGrain pg(g);
        if (auto pc = collision::collidePolyhedronPlane(pg.placed, point, inward, tol))
          out.push_back(fromPolyhedronContact(i, static_cast<int>(w), *pc));
      }
    }
  }
  return out;
}

}  // namespace confpack::analysis
