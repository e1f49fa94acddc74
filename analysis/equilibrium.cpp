#include "analysis/equilibrium.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace confpack::analysis {

namespace {

// Calls visit(grain, leverArm, forceOnGrain) for every contact point of every contact, once for
// each grain of the pair. Lever arms use the minimum image so that pairs across a periodic
// boundary put the right moment on both grains (core/contact.hpp conventions).
template <class Visit>
void forEachPointForce(const core::Packing& p, Visit&& visit) {
  const int n = static_cast<int>(p.grains.size());
  for (const core::Contact& c : *p.contacts) {
    if (c.a < 0 || c.a >= n || c.b >= n)
      throw std::invalid_argument(fmt::format("contacts: grain index out of range in contact ({}, {})", c.a, c.b));
    for (const core::ContactPoint& pt : c.points) {
      const core::Vec3 fOnB = pt.normalForce * c.normal + pt.tangentForce;
      visit(c.a, p.box.minimumImage(pt.position - p.grains[c.a].position), core::Vec3(-fOnB));
      if (!core::isWall(c.b)) visit(c.b, p.box.minimumImage(pt.position - p.grains[c.b].position), fOnB);
    }
  }
}

}  // namespace

core::Mat3 contactStress(const core::Packing& packing, const BulkRegion& region, bool* usedBulk) {
  if (!packing.contacts) throw std::invalid_argument("equilibrium: the packing has no contact list");
  bool anyInBulk = false;
  for (const core::Grain& g : packing.grains) anyInBulk = anyInBulk || region.contains(g.position.z());
  double volume = region.volume(packing.box);
  if (!anyInBulk || !(volume > 0.0)) {
    anyInBulk = false;
    volume = packing.box.lengthX * packing.box.width * region.freeSurface;
  }
  if (usedBulk) *usedBulk = anyInBulk;
  core::Mat3 s = core::Mat3::Zero();
  if (!(volume > 0.0)) return s;
  forEachPointForce(packing, [&](int i, const core::Vec3& lever, const core::Vec3& f) {
    if (anyInBulk && !region.contains(packing.grains[i].position.z())) return;
    s -= lever * f.transpose();
  });
  s /= volume;
  return 0.5 * (s + s.transpose());
}

EquilibriumReport equilibrium(const core::Packing& packing, const std::vector<core::BodyState>& states,
                              const core::Vec3& gravity, double density, double forceRatio, double momentRatio,
                              double kineticRatio, const BulkRegionDef& regionDef) {
  if (!packing.contacts) throw std::invalid_argument("equilibrium: the packing has no contact list");
  const std::size_t n = packing.grains.size();
  if (!states.empty() && states.size() != n)
    throw std::invalid_argument(fmt::format("equilibrium: states has {} entries for {} grains", states.size(), n));

  EquilibriumReport r;
  const BulkRegion region = bulkRegion(packing, regionDef);
  r.pressure = contactStress(packing, region, &r.pressureFromBulk).trace() / 3.0;

  std::vector<core::Vec3> force(n), moment(n, core::Vec3::Zero());
  for (std::size_t i = 0; i < n; ++i) force[i] = density * packing.grains[i].volume() * gravity;
  forEachPointForce(packing, [&](int i, const core::Vec3& lever, const core::Vec3& f) {
    force[i] += f;
    moment[i] += lever.cross(f);
  });

  const double inf = std::numeric_limits<double>::infinity();
  const double scale = r.pressure > 0.0 ? 1.0 / r.pressure : inf;
  for (std::size_t i = 0; i < n; ++i) {
    const core::Grain& g = packing.grains[i];
    double ek = 0.0, settling = 0.0;  // settling: without a spin that moves no boundary
    if (!states.empty()) {
      const double m = density * g.volume();
      const core::Mat3 rot = g.orientation.toRotationMatrix();
      const core::Mat3 inertia = rot * g.bodyInertia(density) * rot.transpose();
      const core::Vec3& w = states[i].angularVelocity;
      const double translational = 0.5 * m * states[i].velocity.squaredNorm();
      ek = translational + 0.5 * w.dot(inertia * w);
      settling = g.spinMovesBoundary() ? ek : translational;
    }
    const double d = g.size;
    // 0 * inf would be NaN: an exactly balanced grain has ratio 0 even when P = 0.
    auto ratio = [&](double value, double dPow) { return value == 0.0 ? 0.0 : value * scale / dPow; };
    const double fr = ratio(force[i].norm(), d * d);
    const double mr = ratio(moment[i].norm(), d * d * d);
    const double kr = ratio(ek, d * d * d);
    if (fr > r.maxForceRatio || r.worstGrain < 0) {
      r.maxForceRatio = std::max(r.maxForceRatio, fr);
      if (fr >= r.maxForceRatio) r.worstGrain = static_cast<int>(i);
    }
    r.maxMomentRatio = std::max(r.maxMomentRatio, mr);
    r.maxKineticRatio = std::max(r.maxKineticRatio, kr);
    r.meanKineticRatio += kr / static_cast<double>(n);
    r.meanSettlingKineticRatio += ratio(settling, d * d * d) / static_cast<double>(n);
  }
  r.reached = r.pressure > 0.0 && r.maxForceRatio < forceRatio && r.maxMomentRatio < momentRatio &&
              r.maxKineticRatio < kineticRatio;
  return r;
}

void to_json(nlohmann::json& j, const EquilibriumReport& r) {
  auto finite = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  j = {{"reached", r.reached},
       {"max_force_ratio", finite(r.maxForceRatio)},
       {"max_moment_ratio", finite(r.maxMomentRatio)},
       {"max_kinetic_ratio", finite(r.maxKineticRatio)},
       {"mean_kinetic_ratio", finite(r.meanKineticRatio)},
       {"pressure", r.pressure},
       {"worst_grain", r.worstGrain},
       {"pressure_from_bulk", r.pressureFromBulk}};
}

}  // namespace confpack::analysis
