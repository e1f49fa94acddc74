#include "backends/nscd/narrow_phase.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "core/parallel_failure.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace confpack::nscd {

using core::Vec3;
using core::WallId;

bool collideSphereSphere(const Vec3& pa, double ra, const Vec3& pbImage, double rb, double alert,
                         ContactGeometry& out) {
  const Vec3 d = pbImage - pa;
  const double dist = d.norm();
  const double gap = dist - ra - rb;
  if (gap >= alert || dist <= 0.0) return false;
  out.type = core::ContactType::Simple;
  out.feature = 0;
  out.normal = d / dist;
  out.pointCount = 1;
  out.points[0] = pa + out.normal * (ra + 0.5 * gap);
  out.gaps[0] = gap;
  return true;
}

bool collideSphereWall(const Vec3& pa, double ra, WallId w, const core::BoxDef& box, double alert,
                       ContactGeometry& out) {
  const Vec3 inward = core::BoxDef::wallNormal(w);
  const double gap = inward.dot(pa - box.wallPoint(w)) - ra;
  if (gap >= alert) return false;
  out.b = static_cast<int>(w);
  out.shiftX = out.shiftY = 0;
  out.type = core::ContactType::Simple;
  out.feature = 0;
  out.normal = -inward;
  out.pointCount = 1;
  out.points[0] = pa + out.normal * (ra + 0.5 * gap);
  out.gaps[0] = gap;
  return true;
}

std::uint32_t featureKey(const collision::Feature& a, const collision::Feature& b) {
  // 2 bits of kind and 14 bits of (index + 1) per body; index -1 (see collision::Feature) maps to 0.
  auto pack = [](const collision::Feature& f) {
    return (static_cast<std::uint32_t>(f.kind) << 14) | (static_cast<std::uint32_t>(f.index + 1) & 0x3fffu);
  };
  return (pack(a) << 16) | pack(b);
}

void fromPolyhedronContact(const collision::PolyhedronContact& pc, bool flip, ContactGeometry& out) {
  out.type = pc.type;
  out.normal = flip ? Vec3(-pc.normal) : pc.normal;
  out.feature = flip ? featureKey(pc.featureB, pc.featureA) : featureKey(pc.featureA, pc.featureB);
  out.pointCount = std::min<int>(static_cast<int>(pc.points.size()), kMaxContactPoints);
  for (int p = 0; p < out.pointCount; ++p) {
    out.points[p] = pc.points[p];
    out.gaps[p] = pc.pointGaps[p];
  }
}

NarrowPhase::NarrowPhase(const core::BoxDef& box, const std::vector<core::Grain>& grains, double alertFraction,
                         double commonPlaneBand)
    : box_(box), alertFraction_(alertFraction), commonPlaneBand_(commonPlaneBand) {
  for (const core::Grain& g : grains) {
    if (!(g.size > 0.0) || !std::isfinite(g.size))
      throw std::invalid_argument("nscd: every grain size must be a positive number");
    poly_.push_back(g.shape == core::ShapeKind::Pinacoid ? g.polyhedron() : core::ConvexPolyhedron{});
    shape_.push_back(g.shape);
    hasPolyhedra_ = hasPolyhedra_ || g.shape != core::ShapeKind::Sphere;
    radius_.push_back(g.boundingRadius());
    size_.push_back(g.size);
  }
}

double NarrowPhase::maxReach() const {
  double r = 0.0;
  for (std::size_t i = 0; i < radius_.size(); ++i) r = std::max(r, reach(static_cast<int>(i)));
  return r;
}

void NarrowPhase::collidePair(const CandidatePair& pair, const std::vector<Vec3>& positions,
                              const std::vector<core::Quat>& orientations, std::vector<ContactGeometry>& out) const {
  collidePairIn(pair, positions, orientations, nullptr, out);
}

void NarrowPhase::placeGrain(int i, const std::vector<Vec3>& positions, const std::vector<core::Quat>& orientations) {
  if (shape_[i] == core::ShapeKind::Sphere) return;
  world_[i].assign({&poly_[i], positions[i], orientations[i].toRotationMatrix()});
}

void NarrowPhase::collidePairIn(const CandidatePair& pair, const std::vector<Vec3>& positions,
                                const std::vector<core::Quat>& orientations,
                                const std::vector<collision::WorldPolyhedron>* world,
                                std::vector<ContactGeometry>& out) const {
  const int a = pair.a, b = pair.b;
  const Vec3 pb = positions[b] + Vec3(pair.shiftX * box_.lengthX, pair.shiftY * box_.width, 0.0);
  const double alert = alertFraction_ * std::min(size_[a], size_[b]);
  ContactGeometry c;
  c.a = a;
  c.b = b;
  c.shiftX = pair.shiftX;
  c.shiftY = pair.shiftY;
  const bool sphereA = shape_[a] == core::ShapeKind::Sphere, sphereB = shape_[b] == core::ShapeKind::Sphere;
  if (sphereA && sphereB) {
    if (collideSphereSphere(positions[a], radius_[a], pb, radius_[b], alert, c)) out.push_back(c);
    return;
  }
  // Polyhedra: the exact SAT routines of collision/polyhedron_contact (shared with analysis), with
  // every point that can touch within the alert distance (contact_region.hpp, "Points within reach"),
  // or the common plane's reading of them (contact_detection "common_plane").
  auto placed = [&](int i, const Vec3& p) {
    return collision::PlacedPolyhedron{&poly_[i], p, orientations[i].toRotationMatrix()};
  };
  std::optional<collision::PolyhedronContact> pc;
  bool flip = false;
  if (!sphereA && !sphereB) {
    // The bounding spheres first, then the pair in world coordinates: each grain's own from
    // `world` when given; an image across a periodic side is placed for the pair (placing it by
    // shifting the grain's copy would round differently).
    const double reach = poly_[a].boundingRadius() + poly_[b].boundingRadius() + alert;
    if ((pb - positions[a]).squaredNorm() > reach * reach) return;
    const auto collide = [&](const collision::WorldPolyhedron& A, const collision::WorldPolyhedron& B) {
      return commonPlaneBand_ > 0.0 ? collision::collideCommonPlane(A, B, alert, commonPlaneBand_)
                                    : collision::collideWorldPolyhedra(A, B, alert, collision::kFeatureAngleTol, alert);
    };
    if (world == nullptr)
      pc = collide(collision::WorldPolyhedron(placed(a, positions[a])), collision::WorldPolyhedron(placed(b, pb)));
    else if (pair.shiftX == 0 && pair.shiftY == 0)
      pc = collide((*world)[a], (*world)[b]);
    else
      pc = collide((*world)[a], collision::WorldPolyhedron(placed(b, pb)));
  } else if (!sphereA) {
    pc = collision::collidePolyhedronSphere(placed(a, positions[a]), pb, radius_[b], alert);
  } else {
    pc = collision::collidePolyhedronSphere(placed(b, pb), positions[a], radius_[a], alert);
    flip = true;
  }
  if (!pc || pc->points.empty()) return;
  fromPolyhedronContact(*pc, flip, c);
  out.push_back(c);
}

void NarrowPhase::collideWalls(int i, const std::vector<Vec3>& positions, const std::vector<core::Quat>& orientations,
                               std::vector<ContactGeometry>& out) const {
  const double alert = alertFraction_ * size_[i];
  const Vec3& p = positions[i];
  ContactGeometry c;
  c.a = i;
  if (shape_[i] == core::ShapeKind::Pinacoid) {
    const collision::PlacedPolyhedron placed{&poly_[i], p, orientations[i].toRotationMatrix()};
    auto wall = [&](WallId w, double distance) {
      if (distance - radius_[i] >= alert) return;  // bounding-sphere rejection
      const auto pc = collision::collidePolyhedronPlane(placed, box_.wallPoint(w), core::BoxDef::wallNormal(w), alert);
      if (!pc || pc->points.empty()) return;
      c.b = static_cast<int>(w);
      fromPolyhedronContact(*pc, false, c);
      out.push_back(c);
    };
    wall(WallId::Floor, p.z());
    if (box_.periodicY) return;
    wall(WallId::SideLow, p.y());
    wall(WallId::SideHigh, box_.width - p.y());
    return;
  }
  // Cheap rejection on the bounding radius before the exact routine.
  if (p.z() - radius_[i] < alert && collideSphereWall(p, radius_[i], WallId::Floor, box_, alert, c)) out.push_back(c);
  if (box_.periodicY) return;
  if (p.y() - radius_[i] < alert && collideSphereWall(p, radius_[i], WallId::SideLow, box_, alert, c)) out.push_back(c);
  if (box_.width - p.y() - radius_[i] < alert && collideSphereWall(p, radius_[i], WallId::SideHigh, box_, alert, c))
    out.push_back(c);
}

void NarrowPhase::collideAll(const std::vector<CandidatePair>& pairs, const std::vector<Vec3>& positions,
                             const std::vector<core::Quat>& orientations, std::vector<ContactGeometry>& out,
                             int threads) {
  out.clear();
  const std::size_t nPairs = pairs.size(), nGrains = shape_.size();
  if (hasPolyhedra_ && world_.size() != nGrains) world_.resize(nGrains);
  const std::size_t useful = std::max<std::size_t>(1, nPairs / kMinPairsPerThread);
  const int wanted = hasPolyhedra_ ? static_cast<int>(std::min<std::size_t>(std::max(1, threads), useful)) : 1;
#ifdef _OPENMP
  if (choice_.maxThreads() != std::max(1, threads)) choice_ = ThreadChoice(threads);
  const bool timed = wanted > 1;
  const auto start = std::chrono::steady_clock::now();
  auto record = [&] {
    if (timed) choice_.record(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  };
  if (wanted > 1 && choice_.next() > 1) {
    if (static_cast<int>(threadContacts_.size()) < wanted) threadContacts_.resize(wanted);
    for (ThreadContacts& tc : threadContacts_) {  // a smaller team leaves some unused
      tc.pairs.clear();
      tc.walls.clear();
    }
    auto chunk = [](std::size_t n, int t, int team) { return n * static_cast<std::size_t>(t) / team; };
    // A contact list that cannot grow throws std::bad_alloc in a thread: kept, every thread still
    // reaches the barrier, the joining is skipped and the exception rethrown after the region.
    core::ParallelFailure failure;
#pragma omp parallel num_threads(wanted)
    {
      const int t = omp_get_thread_num(), team = omp_get_num_threads();
      ThreadContacts& mine = threadContacts_[t];
      std::vector<ContactGeometry>& pairOut = t == 0 ? out : mine.pairs;
      failure.capture([&] {
        for (std::size_t i = chunk(nGrains, t, team); i < chunk(nGrains, t + 1, team); ++i)
          placeGrain(static_cast<int>(i), positions, orientations);
      });
#pragma omp barrier
      failure.capture([&] {
        if (failure.failed()) return;
        for (std::size_t k = chunk(nPairs, t, team); k < chunk(nPairs, t + 1, team); ++k)
          collidePairIn(pairs[k], positions, orientations, &world_, pairOut);
        for (std::size_t i = chunk(nGrains, t, team); i < chunk(nGrains, t + 1, team); ++i)
          collideWalls(static_cast<int>(i), positions, orientations, mine.walls);
      });
#pragma omp barrier
#pragma omp single
      if (!failure.failed()) {
        failure.capture([&] {
          // Layout: pairs of thread 0 (already in place), 1, ..., then walls of thread 0, 1, ...
          std::size_t at = out.size();
          threadContacts_[0].pairStart = 0;
          for (std::size_t u = 1; u < threadContacts_.size(); ++u) {
            threadContacts_[u].pairStart = at;
            at += threadContacts_[u].pairs.size();
          }
          for (ThreadContacts& tc : threadContacts_) {
            tc.wallStart = at;
            at += tc.walls.size();
          }
          out.resize(at);
        });
      }
      // After the single's barrier every thread sees the same failed().
      if (!failure.failed()) {
        failure.capture([&] {
          if (t != 0)
            std::copy(mine.pairs.begin(), mine.pairs.end(), out.begin() + static_cast<std::ptrdiff_t>(mine.pairStart));
          std::copy(mine.walls.begin(), mine.walls.end(), out.begin() + static_cast<std::ptrdiff_t>(mine.wallStart));
        });
      }
    }
    failure.rethrow();
    record();
    return;
  }
#endif
  if (hasPolyhedra_)
    for (std::size_t i = 0; i < nGrains; ++i) placeGrain(static_cast<int>(i), positions, orientations);
  for (const CandidatePair& p : pairs) collidePairIn(p, positions, orientations, &world_, out);
  for (std::size_t i = 0; i < nGrains; ++i) collideWalls(static_cast<int>(i), positions, orientations, out);
#ifdef _OPENMP
  record();
#endif
}

}  // namespace confpack::nscd
