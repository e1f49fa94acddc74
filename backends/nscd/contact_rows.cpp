#include "backends/nscd/contact_rows.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace confpack::nscd {

using core::Vec3;

namespace {

/// The sweep rows are split into two blocks (build()) from a box length of this many largest
/// lever arms: the two edge strips, 2 lever arms wide each and swept serially, then hold at most
/// a quarter of the rows (a tenth at L_x = 20 d).
constexpr double kSweepSplitLength = 16.0;

// c of the contact law (see the header): exact closing of open gaps; an overlap removed by a
// bounded fraction per step ("gap") or held ("velocity").
double gapBias(double gap, double dt, const NscdSettings& s) {
  if (gap >= 0.0) return gap / dt;
  if (s.contactLaw == ContactLaw::Velocity) return 0.0;
  return std::max(s.gapCorrection * gap / dt, -s.maxCorrectionVelocity);
}

}  // namespace

// Tangential update of a side-wall friction point at its current normal impulse: one local
// Gauss-Seidel step, over-relaxed by omega, projected on the Coulomb disc ||r_t|| <= mu r_n.
// Returns the change (d1, d2).
std::pair<double, double> updateTangent(FrictionRow& row, BodyVelocity& va, double omega) {
  const double ut1 = -(row.t1.dot(va.v) + row.axt1.dot(va.w));
  const double ut2 = -(row.t2.dot(va.v) + row.axt2.dot(va.w));
  double rt1 = row.rt1 - omega * ut1 * row.invWt;
  double rt2 = row.rt2 - omega * ut2 * row.invWt;
  const double limit = row.mu * row.rn;
  const double norm = std::hypot(rt1, rt2);
  if (norm > limit) {
    const double s = norm > 0.0 ? limit / norm : 0.0;
    rt1 *= s;
    rt2 *= s;
  }
  const double d1 = rt1 - row.rt1, d2 = rt2 - row.rt2;
  row.rt1 = rt1;
  row.rt2 = rt2;
  va.v -= row.invMa * (d1 * row.t1 + d2 * row.t2);
  va.w -= d1 * row.iaAxt1 + d2 * row.iaAxt2;
  return {d1, d2};
}

void ContactRows::build(const std::vector<ContactGeometry>& contacts, const std::vector<Vec3>& positions,
                        const std::vector<BodyInverseMass>& bodies, const core::BoxDef& box,
                        const core::WallMaterial& walls, double dt, const NscdSettings& settings) {
  normalRows_.clear();
  frictionRows_.clear();
  rowRef_.clear();
  impulseOfRow_.clear();  // until a solve stores them
  warmNormalsInSolve_ = settings.solver != SolverKind::Nlgs;
  int contactIndex = -1;
  double leverMax = 0.0;
  const int staticBody = static_cast<int>(bodies.size()) - 1;
  for (const ContactGeometry& c : contacts) {
    ++contactIndex;
    const bool wall = c.b < 0;
    const double mu = wall ? walls.frictionOf(static_cast<core::WallId>(c.b)) : 0.0;
    const BodyInverseMass& ma = bodies[c.a];
    if (wall && mu > 0.0) {
      rowRef_.push_back({true, static_cast<int>(frictionRows_.size())});
      // Fixed tangent basis of a side wall (normal +-y): t1 = x, t2 = z. Fixed axes make the
      // cached tangential impulses meaningful from one step to the next.
      const Vec3 t1 = Vec3::UnitX(), t2 = Vec3::UnitZ();
      for (int p = 0; p < c.pointCount; ++p) {
        FrictionRow row;
        row.a = c.a;
        row.n = c.normal;
        row.t1 = t1;
        row.t2 = t2;
        const Vec3 la = c.points[p] - positions[c.a];
        row.axn = la.cross(c.normal);
        row.axt1 = la.cross(t1);
        row.axt2 = la.cross(t2);
        row.iaAxn = ma.invInertia * row.axn;
        row.iaAxt1 = ma.invInertia * row.axt1;
        row.iaAxt2 = ma.invInertia * row.axt2;
        row.invMa = ma.invMass;
        row.invWnn = 1.0 / (ma.invMass + row.axn.dot(row.iaAxn));
        // W_tt = (1/m) I_2 + [(l x t_i).I^-1 (l x t_j)]; its largest eigenvalue in closed form.
        const double w11 = ma.invMass + row.axt1.dot(row.iaAxt1);
        const double w22 = ma.invMass + row.axt2.dot(row.iaAxt2);
        const double w12 = row.axt1.dot(row.iaAxt2);
        const double half = 0.5 * (w11 - w22);
        row.invWt = 1.0 / (0.5 * (w11 + w22) + std::sqrt(half * half + w12 * w12));
        row.bias = gapBias(c.gaps[p], dt, settings);
        row.mu = mu;
        frictionRows_.push_back(row);
      }
      continue;
    }
    rowRef_.push_back({false, static_cast<int>(normalRows_.size())});
    const int b = wall ? staticBody : c.b;
    const BodyInverseMass& mb = bodies[b];
    const Vec3 pb =
        wall ? Vec3::Zero() : Vec3(positions[c.b] + Vec3(c.shiftX * box.lengthX, c.shiftY * box.width, 0.0));
    for (int p = 0; p < c.pointCount; ++p) {
      NormalRow row;
      row.a = c.a;
      row.b = b;
      row.n = c.normal;
      const Vec3 la = c.points[p] - positions[c.a];
      const Vec3 lb = wall ? Vec3::Zero() : Vec3(c.points[p] - pb);
      row.axn = la.cross(c.normal);
      row.bxn = lb.cross(c.normal);
      row.iaAxn = ma.invInertia * row.axn;
      row.ibBxn = mb.invInertia * row.bxn;
      row.invMa = ma.invMass;
      row.invMb = mb.invMass;
      row.invW = 1.0 / (ma.invMass + mb.invMass + row.axn.dot(row.iaAxn) + row.bxn.dot(row.ibBxn));
      row.bias = gapBias(c.gaps[p], dt, settings);
      row.z = c.points[p].z();
      row.x = c.points[p].x();
      leverMax = std::max({leverMax, la.norm(), lb.norm()});
      row.c = contactIndex;
      row.p = p;
      normalRows_.push_back(row);
    }
  }
  // Sweep order: frictionless rows from the lowest contact point to the highest (ties by bodies,
  // contact and point, so the order depends only on the configuration). See the header.
  // For MPRGP's Gauss-Seidel preconditioner on a box long enough, first the rows of two blocks
  // that share no grain, each bottom to top, then the rest (see the header): two threads sweep
  // the blocks at once. A grain's contact points lie within `leverMax` of its centre, so two
  // rows of one grain are at most 2 leverMax apart along x; rows farther than leverMax from both
  // block edges (x = 0 and x = L/2, periodic) on opposite sides are farther apart than that.
  const int n = static_cast<int>(normalRows_.size());
  const double L = box.lengthX, half = 0.5 * L;
  const bool split = settings.solver == SolverKind::Mprgp &&
                     (settings.preconditioner == PreconditionerKind::SymmetricGaussSeidel ||
                      settings.preconditioner == PreconditionerKind::Switching) &&
                     L >= kSweepSplitLength * leverMax;
  for (NormalRow& row : normalRows_) {
    const double x = core::BoxDef::wrapCoordinate(row.x, L);
    const double edge = std::min({x, L - x, std::abs(x - half)});
    row.segment = !split || edge <= leverMax ? 2 : (x < half ? 0 : 1);
  }
  // Sorted as compact keys (the rows themselves are ten times larger: comparing through an index
  // into them missed the cache at every comparison).
  sortKeys_.resize(n);
  for (int k = 0; k < n; ++k) {
    const NormalRow& r = normalRows_[k];
    sortKeys_[k] = {r.segment, r.z, r.a, r.b, r.c, r.p, k};
  }
  std::sort(sortKeys_.begin(), sortKeys_.end(), [](const SortKey& x, const SortKey& y) {
    if (x.segment != y.segment) return x.segment < y.segment;
    if (x.z != y.z) return x.z < y.z;
    if (x.a != y.a) return x.a < y.a;
    if (x.b != y.b) return x.b < y.b;
    if (x.c != y.c) return x.c < y.c;
    return x.p < y.p;
  });
  sorted_.resize(n);
  slot_.resize(n);
  sweepBlockEnd_[0] = sweepBlockEnd_[1] = 0;
  for (int k = 0; k < n; ++k) {
    const int from = sortKeys_[k].index;
    sorted_[k] = normalRows_[from];
    slot_[from] = k;
    if (sorted_[k].segment == 0) sweepBlockEnd_[0] = k + 1;
    if (sorted_[k].segment <= 1) sweepBlockEnd_[1] = k + 1;
  }
  sweepBlockEnd_[1] = std::max(sweepBlockEnd_[1], sweepBlockEnd_[0]);
  normalRows_.swap(sorted_);
}

std::array<std::vector<int>, 2> ContactRows::sweepBlockBodies(int world) const {
  std::array<std::vector<int>, 2> out;
  for (int blk = 0; blk < 2; ++blk) {
    for (int k = blk == 0 ? 0 : sweepBlockEnd_[0]; k < sweepBlockEnd_[blk]; ++k)
      for (const int body : {normalRows_[k].a, normalRows_[k].b})
        if (body != world) out[blk].push_back(body);
    std::sort(out[blk].begin(), out[blk].end());
    out[blk].erase(std::unique(out[blk].begin(), out[blk].end()), out[blk].end());
  }
  return out;
}

void ContactRows::warmStart(const ContactCache& cache, const std::vector<ContactGeometry>& contacts, double dt,
                            std::vector<BodyVelocity>& vel) {
  const double scale = cache.dt() > 0.0 ? dt / cache.dt() : 0.0;
  std::size_t cursor = 0;  // contacts come mostly in key order (the cache's)
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    const ContactGeometry& g = contacts[c];
    const CachedContact* old = cache.find(ContactKey::of(g), cursor);
    if (old == nullptr) continue;
    // Same point count: point by point. Otherwise the previous total is shared equally (the
    // points of a re-clipped face do not correspond one to one).
    auto take = [&](const std::array<double, kMaxContactPoints>& v, int p) {
      if (old->pointCount == g.pointCount) return scale * v[p];
      double s = 0.0;
      for (int q = 0; q < old->pointCount; ++q) s += v[q];
      return scale * s / g.pointCount;
    };
    const RowRef ref = rowRef_[c];
    for (int p = 0; p < g.pointCount; ++p) {
      if (ref.friction) {
        FrictionRow& row = frictionRows_[ref.first + p];
        row.rn = take(old->normal, p);
        row.rt1 = take(old->tangent1, p);
        row.rt2 = take(old->tangent2, p);
        // Impulse on a is minus that on the wall; MPRGP applies the normal part itself.
        const double rn = warmNormalsInSolve_ ? 0.0 : row.rn;
        BodyVelocity& va = vel[row.a];
        va.v -= row.invMa * (rn * row.n + row.rt1 * row.t1 + row.rt2 * row.t2);
        va.w -= rn * row.iaAxn + row.rt1 * row.iaAxt1 + row.rt2 * row.iaAxt2;
      } else {
        NormalRow& row = normalRows_[slot_[ref.first + p]];
        row.r = take(old->normal, p);
        if (warmNormalsInSolve_) continue;
        vel[row.a].v -= row.invMa * row.r * row.n;
        vel[row.a].w -= row.r * row.iaAxn;
        vel[row.b].v += row.invMb * row.r * row.n;
        vel[row.b].w += row.r * row.ibBxn;
      }
    }
  }
}

bool ContactRows::turnsNoBody() const {
  constexpr double kNoLever = 1e-9;
  const auto small = [](const core::Vec3& v) { return v.squaredNorm() <= kNoLever * kNoLever; };
  for (const NormalRow& row : normalRows_)
    if (!small(row.axn) || !small(row.bxn)) return false;
  for (const FrictionRow& row : frictionRows_)
    if (!small(row.axn)) return false;
  return true;
}

double ContactRows::normalImpulse(int c, int p) const {
  const RowRef ref = rowRef_[c];
  return ref.friction ? frictionRows_[ref.first + p].rn : impulseOfRow_[static_cast<std::size_t>(ref.first + p)];
}

Vec3 ContactRows::tangentImpulse(int c, int p) const {
  const RowRef ref = rowRef_[c];
  if (!ref.friction) return Vec3::Zero();
  const FrictionRow& row = frictionRows_[ref.first + p];
  return row.rt1 * row.t1 + row.rt2 * row.t2;
}

void ContactRows::exportImpulses(const std::vector<ContactGeometry>& contacts, std::vector<CachedContact>& out) const {
  out.clear();
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    const ContactGeometry& g = contacts[c];
    CachedContact e;
    e.key = ContactKey::of(g);
    e.pointCount = g.pointCount;
    const RowRef ref = rowRef_[c];
    for (int p = 0; p < g.pointCount; ++p) {
      if (ref.friction) {
        const FrictionRow& row = frictionRows_[ref.first + p];
        e.normal[p] = row.rn;
        e.tangent1[p] = row.rt1;
        e.tangent2[p] = row.rt2;
      } else {
        e.normal[p] = impulseOfRow_[static_cast<std::size_t>(ref.first + p)];
      }
    }
    out.push_back(e);
  }
}

}  // namespace confpack::nscd
