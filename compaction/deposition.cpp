// Geometric deposition (docs/model.md, "Deposition"): sequential ballistic deposition with rolling
// to a three-point seat (Visscher & Bolsterli, Nature 239, 504 (1972); Jodrey & Tory, Simulation
// 32, 1 (1979)), computed with closed-form geometry only.
//
// The moving placeholder is a point c (its centre) in the free space
//     F = { c : |c - c_k| >= D for every placed centre c_k (periodic images included),
//               z >= D/2 (floor), D/2 <= y <= W - D/2 (side walls, if any) }.
// Each boundary piece of F met by c is a "support" with a unit normal n_i pointing into F.
// Quasi-static descent under gravity g = -e_z: the motion direction is the projection of g on
// the cone of admissible directions { d : d . n_i >= 0 }, i.e. the KKT point
//     d = g + sum_{i in S} lambda_i n_i,   lambda_i >= 0,   d . n_i = 0 (i in S),
//     d . n_j >= 0 (j touching, not in S),
// where lambda_i are the (frictionless) support forces. We find S by enumerating the subsets of
// the touching supports (at most 6, subsets of at most 3 independent normals: 42 tiny linear
// solves). The motion that keeps the supports of S is then a known curve:
//     S = {}                 vertical fall (a side wall in S changes nothing: it is vertical);
//     S = {sphere j}         great circle of the sphere |c - c_j| = D in the vertical plane;
//     S = {sphere j, wall}   circle where that sphere meets the plane y = D/2 (or W - D/2);
//     S = {spheres j, k}     circle |c - c_j| = |c - c_k| = D;
//     S has 3 supports, or contains the floor: d = 0, the placeholder is seated.
// Three supports with lambda >= 0 is exactly "the centre projects inside the triangle of the
// contact points" for three spheres, and its generalisation when a wall is one of them.
// Along a curve the support forces change; each curve is followed only while they stay >= 0:
// one sphere until its equator (lambda = e_z . n = 0), the sphere-wall circle until the level of
// the sphere's centre, the two-sphere circle until the height where the upper sphere's force
// vanishes (derived in arcOnTwoSpheres). Every other event (touching a new sphere, the floor or
// a wall) is a root of g(psi) = A + B cos(psi) + C sin(psi) along the arc, or of a quadratic
// along the fall: all moves are exact, none is a time step.
#include "compaction/deposition.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "collision/cell_list.hpp"

namespace confpack::compaction {

using namespace core;  // the model's types: every name here is geometry over them

namespace {

// Tolerances, relative to the placeholder diameter D. Positions are computed to about 1e-15 D;
// these sit well above round-off and well below the 1e-9 D overlap bound the deposit promises.
constexpr double kTouchTol = 1e-10;        // a support whose gap is below this touches [D]
constexpr double kPenetrationTol = 1e-12;  // a move stops this far inside a newly met support [D]
constexpr double kMultiplierTol = 1e-12;   // support force accepted as non-negative [-]
constexpr double kDirectionTol = 1e-12;    // motion accepted as not entering a support [-]
// Second chance when no subset passes kDirectionTol: a support met on its equator at the
// kPenetrationTol threshold has a normal tilted by up to sqrt(2 kPenetrationTol) ~ 1.5e-6 out
// of the horizontal, which can leave two nearly opposite supports (pinched at equal heights, as
// happens in a W = D channel) with no admissible subset. The moves' event tests still refuse any
// penetration deeper than kPenetrationTol, so the relaxed tolerance cannot create overlaps.
constexpr double kRelaxedDirectionTol = 1e-5;
constexpr double kDegenerateTol = 1e-10;  // Gram determinant below which normals are dependent [-]
constexpr double kValidGapTol = 1e-10;    // a fallback seat may overlap at most this [D]
// A seat is normally found in 3 to 10 moves; far more means a degenerate cycle (see settle()).
constexpr int kMaxMoves = 200;
// Generically 3 supports touch at once; 6 leaves room for symmetric coincidences.
constexpr std::size_t kMaxTouching = 6;

enum class SupportKind { Sphere, Floor, WallLow, WallHigh };

struct Support {
  SupportKind kind = SupportKind::Floor;
  int id = -1;                 // placeholder index (spheres only)
  Vec3 centre = Vec3::Zero();  // the image of that placeholder next to the moving one [d_L]
  double gap = 0.0;            // distance to contact, negative when overlapping [d_L]
};

// A circular arc c(psi) = m + rho (cos psi e1 + sin psi e2), psi in [0, psiEnd], going down.
struct Arc {
  Vec3 m = Vec3::Zero();
  double rho = 0.0;
  Vec3 e1 = Vec3::UnitX();
  Vec3 e2 = -Vec3::UnitZ();
  double psiEnd = 0.0;
};

// Smallest psi in (0, psiMax] at which A + B cos psi + C sin psi becomes negative, for a function
// that is positive at psi = 0 (A + B > 0). Writing it A + R cos(psi - delta) with R = |(B, C)|,
// delta = atan2(C, B), it is negative on psi - delta in (beta, 2 pi - beta), beta = acos(-A/R);
// since psi = 0 lies outside that interval, the first entry is psi = delta + beta (mod 2 pi).
std::optional<double> firstNegative(double a, double b, double c, double psiMax) {
  const double r = std::hypot(b, c);
  if (!(a < r)) return std::nullopt;
  const double delta = std::atan2(c, b);
  const double beta = std::acos(std::clamp(-a / r, -1.0, 1.0));
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double psi = std::fmod(delta + beta, kTwoPi);
  if (psi < 0.0) psi += kTwoPi;
  if (psi > psiMax) return std::nullopt;
  return psi;
}

// Result of projecting gravity on the cone of admissible motions.
struct Projection {
  bool found = false;
  std::array<int, 3> members{};  // indices into the touching list
  int size = 0;
  Vec3 motion = Vec3::Zero();  // projected gravity d [-]
};

// Support forces lambda = N^-1 e_z of three supports (columns of N the normals), if independent.
std::optional<Vec3> tripleForces(const Vec3& a, const Vec3& b, const Vec3& c) {
  Mat3 n;
  n << a, b, c;
  const double det = n.determinant();
  if (det * det < kDegenerateTol) return std::nullopt;
  return Vec3(n.inverse() * Vec3::UnitZ());
}

// Whether some three of the touching supports hold the placeholder with compressive forces.
bool hasStableTriple(const std::vector<Vec3>& normals) {
  const std::size_t m = normals.size();
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = a + 1; b < m; ++b)
      for (std::size_t c = b + 1; c < m; ++c)
        if (auto lambda = tripleForces(normals[a], normals[b], normals[c]))
          if ((lambda->array() >= -kMultiplierTol).all()) return true;
  return false;
}

// Finds S (see the file comment). Subsets are tried by increasing size, so that a support
// carrying no force (lambda = 0) is released rather than kept: this is what lets a placeholder
// leave a sphere at its equator.
Projection projectGravity(const std::vector<Vec3>& normals, double directionTol) {
  const Vec3 g(0.0, 0.0, -1.0);
  const int m = static_cast<int>(normals.size());
  auto admissible = [&](const Vec3& d, unsigned mask) {
    for (int j = 0; j < m; ++j)
      if (!(mask & (1u << j)) && d.dot(normals[j]) < -directionTol) return false;
    return true;
  };
  for (int k = 0; k <= std::min(3, m); ++k) {
    for (unsigned mask = 0; mask < (1u << m); ++mask) {
      if (std::popcount(mask) != k) continue;
      std::array<int, 3> idx{};
      int c = 0;
      for (int j = 0; j < m; ++j)
        if (mask & (1u << j)) idx[c++] = j;
      // Gram system G lambda = b, G_ab = n_a . n_b, b_a = e_z . n_a, from d . n_a = 0.
      Vec3 d = g;
      bool ok = true;
      if (k == 1) {
        const double lambda = normals[idx[0]].z();
        ok = lambda >= -kMultiplierTol;
        d += lambda * normals[idx[0]];
      } else if (k == 2) {
        const Vec3& n0 = normals[idx[0]];
        const Vec3& n1 = normals[idx[1]];
        const double c01 = n0.dot(n1);
        const double det = 1.0 - c01 * c01;
        if (det < kDegenerateTol) continue;
        const double l0 = (n0.z() - c01 * n1.z()) / det;
        const double l1 = (n1.z() - c01 * n0.z()) / det;
        ok = l0 >= -kMultiplierTol && l1 >= -kMultiplierTol;
        d += l0 * n0 + l1 * n1;
      } else if (k == 3) {
        // Three independent normals: g + N lambda = 0 exactly, lambda = N^-1 e_z.
        const auto lambda = tripleForces(normals[idx[0]], normals[idx[1]], normals[idx[2]]);
        if (!lambda) continue;
        ok = (lambda->array() >= -kMultiplierTol).all();
        d = Vec3::Zero();
      }
      if (!ok || !admissible(d, mask)) continue;
      Projection p;
      p.found = true;
      p.members = idx;
      p.size = k;
      p.motion = d;
      return p;
    }
  }
  return {};
}

// The growing pile and the descent of one placeholder onto it.
class Pile {
 public:
  Pile(const BoxDef& box, double diameter) : box_(box), d_(diameter), r_(0.5 * diameter), grid_(box, diameter) {}

  double top() const { return top_; }

  void add(int id, const Vec3& c) {
    grid_.insert(id, c);
    top_ = std::max(top_, c.z());
  }

  // Settles a placeholder released at c (above the pile). Returns its seat; `settled` is false
  // when the move budget ran out, and then the seat is the lowest overlap-free position visited.
  Vec3 settle(Vec3 c, bool& settled, int& moves) const {
    settled = false;
    Vec3 best = c;
    double bestZ = std::numeric_limits<double>::infinity();
    std::vector<Support> touching;
    std::vector<Vec3> normals;
    std::vector<Support> active;
    for (moves = 0; moves < kMaxMoves; ++moves) {
      const double minGap = touchingSupports(c, touching);
      if (minGap >= -kValidGapTol * d_ && c.z() < bestZ) {
        best = c;
        bestZ = c.z();
      }
      normals.clear();
      for (const Support& s : touching) normals.push_back(normalOf(s, c));
      Projection p = projectGravity(normals, kDirectionTol);
      if (!p.found) p = projectGravity(normals, kRelaxedDirectionTol);
      if (!p.found) break;  // numerically inconsistent contact set: give up on this one
      active.clear();
      int spheres = 0, walls = 0;
      bool floor = false;
      for (int i = 0; i < p.size; ++i) {
        const Support& s = touching[static_cast<std::size_t>(p.members[static_cast<std::size_t>(i)])];
        active.push_back(s);
        if (s.kind == SupportKind::Sphere)
          ++spheres;
        else if (s.kind == SupportKind::Floor)
          floor = true;
        else
          ++walls;
      }
      if (floor || p.size == 3) {
        settled = true;
        return c;
      }
      // Zero projected gravity on one or two supports is an equilibrium: unstable on the top of
      // a sphere or of a groove circle (then the arc below rolls off it), but seated when other
      // touching supports close the pocket, as in the symmetric 4-support pockets that small
      // periods or W = D force (the smaller subset was found first and hides the triple).
      if (p.motion.norm() < kDirectionTol && hasStableTriple(normals)) {
        settled = true;
        return c;
      }
      if (spheres == 0) {
        c = fall(c, active);
      } else if (spheres == 1 && walls == 0) {
        c = roll(arcOnSphere(c, active[0]), active);
      } else if (spheres == 1 && walls == 1) {
        const Support& s = active[0].kind == SupportKind::Sphere ? active[0] : active[1];
        const Support& w = active[0].kind == SupportKind::Sphere ? active[1] : active[0];
        c = roll(arcOnSphereAndWall(c, s, w), active);
      } else {
        c = roll(arcOnTwoSpheres(c, active[0], active[1]), active);
      }
    }
    return best;
  }

 private:
  double wallY(SupportKind k) const { return k == SupportKind::WallLow ? r_ : box_.width - r_; }

  Vec3 normalOf(const Support& s, const Vec3& c) const {
    switch (s.kind) {
      case SupportKind::Sphere:
        return (c - s.centre).normalized();
      case SupportKind::Floor:
        return Vec3::UnitZ();
      case SupportKind::WallLow:
        return Vec3::UnitY();
      case SupportKind::WallHigh:
        return -Vec3::UnitY();
    }
    return Vec3::UnitZ();
  }

  // Fills `out` with the supports touching c (gap < kTouchTol D), closest first, and returns the
  // smallest gap of all supports near c (negative: c overlaps something).
  double touchingSupports(const Vec3& c, std::vector<Support>& out) const {
    out.clear();
    double minGap = std::numeric_limits<double>::infinity();
    const double touch = kTouchTol * d_;
    grid_.forEachNear(c, d_ + touch, [&](const collision::ImageHit& k) {
      const double gap = (c - k.position).norm() - d_;
      minGap = std::min(minGap, gap);
      if (gap <= touch) out.push_back({SupportKind::Sphere, k.id, k.position, gap});
    });
    auto plane = [&](SupportKind kind, double gap) {
      minGap = std::min(minGap, gap);
      if (gap <= touch) out.push_back({kind, -1, Vec3::Zero(), gap});
    };
    plane(SupportKind::Floor, c.z() - r_);
    if (!box_.periodicY) {
      plane(SupportKind::WallLow, c.y() - r_);
      plane(SupportKind::WallHigh, box_.width - r_ - c.y());
    }
    std::stable_sort(out.begin(), out.end(), [](const Support& a, const Support& b) { return a.gap < b.gap; });
    if (out.size() > kMaxTouching) out.resize(kMaxTouching);
    return minGap;
  }

  static bool isActiveSphere(const std::vector<Support>& active, int id, const Vec3& image) {
    for (const Support& s : active)
      if (s.kind == SupportKind::Sphere && s.id == id && (s.centre - image).squaredNorm() < 1e-12) return true;
    return false;
  }

  // Vertical fall from c (side walls in `active` only fix y). Spheres are searched in slabs of
  // 4 D from c downwards: a centre below a slab's bottom z_b is met at height < z_b + D, so the
  // search stops as soon as the best contact found lies above that.
  Vec3 fall(Vec3 c, const std::vector<Support>& active) const {
    for (const Support& s : active)
      if (s.kind == SupportKind::WallLow || s.kind == SupportKind::WallHigh) c.y() = wallY(s.kind);
    double drop = c.z() - r_;  // the floor
    const double slab = 4.0 * d_;
    const double d2 = d_ * d_;
    const double penetration = 2.0 * d2 * kPenetrationTol;  // in |c - c_k|^2 - D^2 units
    for (double zTop = c.z();; zTop -= slab) {
      const double zBottom = zTop - slab;
      grid_.forEachInBox(Vec3(c.x() - d_, c.y() - d_, zBottom), Vec3(c.x() + d_, c.y() + d_, zTop),
                         [&](const collision::ImageHit& k) {
                           const Vec3 w = c - k.position;
                           const double h2 = w.x() * w.x() + w.y() * w.y();
                           const double dz = w.z();
                           if (h2 >= d2 || dz <= 0.0) return;  // never met, or moving away
                           // |w - t e_z|^2 - D^2 = g0 - 2 t dz + t^2 reaches thr at the smaller
                           // root t = q / (dz + sqrt(dz^2 - q)), q = g0 - thr > 0.
                           const double g0 = h2 + dz * dz - d2;
                           const double q = g0 - (std::min(0.0, g0) - penetration);
                           const double disc = dz * dz - q;
                           if (disc < 0.0) return;
                           drop = std::min(drop, q / (dz + std::sqrt(disc)));
                         });
      if (c.z() - drop >= zBottom + d_ || zBottom <= 0.0) break;
    }
    c.z() -= drop;
    return c;
  }

  // Rolling over one sphere: the great circle through c in the vertical plane of c and the
  // sphere's centre, down to the equator, where the support force e_z . n vanishes. With
  // e2 = unit(-e_z + n_z n), z(psi) - z_j = D sin(theta0 - psi), sin(theta0) = n_z, so the equator
  // is at psi = theta0.
  Arc arcOnSphere(Vec3& c, const Support& s) const {
    Arc a;
    a.m = s.centre;
    a.rho = d_;
    a.e1 = (c - s.centre).normalized();
    c = a.m + a.rho * a.e1;  // snap onto the sphere
    a.e2 = -Vec3::UnitZ() + a.e1.z() * a.e1;
    const double n2 = a.e2.norm();
    // On the very top every direction is downhill (an unstable equilibrium): pick +x.
    a.e2 = n2 > 1e-12 ? Vec3(a.e2 / n2) : Vec3((Vec3::UnitX() - a.e1.x() * a.e1).normalized());
    a.psiEnd = std::asin(std::clamp(a.e1.z(), -1.0, 1.0));
    return a;
  }

  // Rolling over a sphere while sliding on a side wall: the circle where the sphere |c - c_j| = D
  // meets the plane y = y_w, centre (x_j, y_w, z_j), radius sqrt(D^2 - (y_j - y_w)^2). The wall's
  // force keeps its sign along the circle (it only depends on y_j - y_w); the sphere's force
  // vanishes at the level of the circle's centre, reached at psi = theta0 as in arcOnSphere.
  Arc arcOnSphereAndWall(Vec3& c, const Support& s, const Support& w) const {
    Arc a;
    const double yw = wallY(w.kind);
    c.y() = yw;
    a.m = Vec3(s.centre.x(), yw, s.centre.z());
    const double off = s.centre.y() - yw;
    const double rho2 = d_ * d_ - off * off;
    if (rho2 <= 0.0) return Arc{c, 0.0, Vec3::UnitX(), -Vec3::UnitZ(), 0.0};
    a.rho = std::sqrt(rho2);
    Vec3 e1 = c - a.m;
    e1.y() = 0.0;
    a.e1 = e1.norm() > 0.0 ? Vec3(e1.normalized()) : Vec3::UnitZ();
    c = a.m + a.rho * a.e1;
    a.e2 = -Vec3::UnitZ() + a.e1.z() * a.e1;
    const double n2 = a.e2.norm();
    a.e2 = n2 > 1e-12 ? Vec3(a.e2 / n2) : Vec3((Vec3::UnitX() - a.e1.x() * a.e1).normalized());
    a.psiEnd = std::asin(std::clamp(a.e1.z(), -1.0, 1.0));
    return a;
  }

  // Rolling in the groove of two spheres j, k at distance s: the circle of centre
  // m = (c_j + c_k)/2, axis u = (c_k - c_j)/s, radius rho = sqrt(D^2 - s^2/4). With w = c - m,
  // n_j = (w + s u/2)/D and n_k = (w - s u/2)/D, so projecting e_z on span(n_j, n_k) = span(w, u):
  //     (lambda_j + lambda_k) rho / D = e_z . w/|w|,   (lambda_j - lambda_k) s / (2D) = u_z.
  // Both forces are >= 0 iff z - z_m >= 2 rho^2 |u_z| / s: a height below which the upper sphere
  // lets go. The arc ends there, or at the circle's lowest point if that came first (it cannot,
  // the lowest point is below z_m, but the bound costs nothing).
  Arc arcOnTwoSpheres(Vec3& c, const Support& j, const Support& k) const {
    Arc a;
    const Vec3 axis = k.centre - j.centre;
    const double s = axis.norm();
    const Vec3 u = axis / s;
    a.m = 0.5 * (j.centre + k.centre);
    const double rho2 = d_ * d_ - 0.25 * s * s;
    Vec3 w = c - a.m;
    w -= w.dot(u) * u;
    if (rho2 <= 0.0 || w.norm() == 0.0) return Arc{c, 0.0, Vec3::UnitX(), -Vec3::UnitZ(), 0.0};
    a.rho = std::sqrt(rho2);
    a.e1 = w.normalized();
    c = a.m + a.rho * a.e1;
    a.e2 = u.cross(a.e1);
    if (a.e2.z() > 0.0) a.e2 = -a.e2;
    Vec3 low = -Vec3::UnitZ() + u.z() * u;
    const double lowNorm = low.norm();
    if (lowNorm < 1e-12) return a;  // horizontal circle: no descent along it (psiEnd = 0)
    low /= lowNorm;
    const double psiLow = std::atan2(low.dot(a.e2), low.dot(a.e1));    // in [0, pi]: e2_z <= 0
    const double hRelease = 2.0 * rho2 * std::abs(u.z()) / s / a.rho;  // in units of rho
    const double g0 = a.e1.z() - hRelease;
    if (g0 <= 0.0) return a;  // already at the release height (psiEnd = 0)
    a.psiEnd = firstNegative(-hRelease, a.e1.z(), a.e2.z(), std::max(0.0, psiLow)).value_or(std::max(0.0, psiLow));
    return a;
  }

  // Follows an arc until its end or until it first enters a support not in `active`. Each
  // support's signed distance along the arc is A + B cos psi + C sin psi: for a sphere at c_k,
  // |m - c_k + rho(...)|^2 - D^2 (squared units); for a plane n . c >= p, n . c(psi) - p. The
  // threshold sits kPenetrationTol below min(0, current value), so a support that is touching
  // but being left is not met again at psi = 0 and every event makes progress.
  Vec3 roll(const Arc& a, const std::vector<Support>& active) const {
    double psi = a.psiEnd;
    if (psi > 0.0) {
      const double d2 = d_ * d_;
      grid_.forEachNear(a.m, a.rho + d_ * (1.0 + kTouchTol), [&](const collision::ImageHit& k) {
        if (isActiveSphere(active, k.id, k.position)) return;
        const Vec3 w = a.m - k.position;
        const double aa = w.squaredNorm() + a.rho * a.rho - d2;
        const double bb = 2.0 * a.rho * w.dot(a.e1);
        const double cc = 2.0 * a.rho * w.dot(a.e2);
        const double thr = std::min(0.0, aa + bb) - 2.0 * d2 * kPenetrationTol;
        if (auto hit = firstNegative(aa - thr, bb, cc, psi)) psi = *hit;
      });
      auto plane = [&](SupportKind kind, const Vec3& n, double p) {
        for (const Support& s : active)
          if (s.kind == kind) return;
        const double aa = n.dot(a.m) - p;
        const double bb = a.rho * n.dot(a.e1);
        const double cc = a.rho * n.dot(a.e2);
        const double thr = std::min(0.0, aa + bb) - d_ * kPenetrationTol;
        if (auto hit = firstNegative(aa - thr, bb, cc, psi)) psi = *hit;
      };
      plane(SupportKind::Floor, Vec3::UnitZ(), r_);
      if (!box_.periodicY) {
        plane(SupportKind::WallLow, Vec3::UnitY(), r_);
        plane(SupportKind::WallHigh, -Vec3::UnitY(), -(box_.width - r_));
      }
    }
    return a.m + a.rho * (std::cos(psi) * a.e1 + std::sin(psi) * a.e2);
  }

  BoxDef box_;
  double d_;
  double r_;
  collision::CellList grid_;
  double top_ = 0.0;
};

// Wraps into [0, L_x) (and [0, W)): floor-based wrapping can return exactly the period for a
// coordinate a hair below 0, which is the same point as 0.
Vec3 wrapStrict(const BoxDef& box, Vec3 p) {
  p = box.wrap(p);
  if (p.x() >= box.lengthX) p.x() = 0.0;
  if (box.periodicY && p.y() >= box.width) p.y() = 0.0;
  return p;
}

}  // namespace

PlaceholderPile depositPlaceholders(const BoxDef& box, double diameter, std::size_t count, Rng& rng,
                                    const ProgressFn& progress) {
  box.validate();
  if (!(diameter > 0.0) || !std::isfinite(diameter))
    throw std::invalid_argument(fmt::format("deposition: placeholder diameter must be positive (got {})", diameter));
  if (box.lengthX < diameter)
    throw std::invalid_argument(
        fmt::format("deposition: length_x {} is shorter than the placeholder diameter {}", box.lengthX, diameter));
  if (box.width < diameter)
    throw std::invalid_argument(
        fmt::format("deposition: width {} is narrower than the placeholder diameter {}", box.width, diameter));
  if (count > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::invalid_argument(fmt::format("deposition: too many placeholders ({})", count));

  const double r = 0.5 * diameter;
  Pile pile(box, diameter);
  PlaceholderPile out;
  out.centres.reserve(count);
  const std::size_t every = std::clamp<std::size_t>(count / 100, 1, 1000);
  std::size_t totalMoves = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const double x = rng.uniform(0.0, box.lengthX);
    const double y = box.periodicY ? rng.uniform(0.0, box.width) : rng.uniform(r, box.width - r);
    // Released a diameter and a half above the highest centre: clear of everything.
    const Vec3 release(x, y, std::max(pile.top(), r) + 1.5 * diameter);
    bool settled = false;
    int moves = 0;
    const Vec3 c = wrapStrict(box, pile.settle(release, settled, moves));
    pile.add(static_cast<int>(i), c);
    out.centres.push_back(c);
    totalMoves += static_cast<std::size_t>(moves);
    if (!settled) ++out.unsettledCount;
    if (progress && ((i + 1) % every == 0 || i + 1 == count)) progress(i + 1, count);
  }
  out.meanMoves = count > 0 ? static_cast<double>(totalMoves) / static_cast<double>(count) : 0.0;
  return out;
}

Vec3 dropPlaceholder(const BoxDef& box, double diameter, const std::vector<Vec3>& pile, double x, double y,
                     bool* settled) {
  box.validate();
  if (!(diameter > 0.0) || !std::isfinite(diameter))
    throw std::invalid_argument(fmt::format("deposition: placeholder diameter must be positive (got {})", diameter));
  const double r = 0.5 * diameter;
  if (!std::isfinite(x) || !std::isfinite(y) || (!box.periodicY && (y < r || y > box.width - r)))
    throw std::invalid_argument(
        fmt::format("deposition: drop point ({}, {}) must keep the placeholder between the side walls", x, y));
  Pile p(box, diameter);
  for (std::size_t i = 0; i < pile.size(); ++i) p.add(static_cast<int>(i), pile[i]);
  bool ok = false;
  int moves = 0;
  const Vec3 c = p.settle(Vec3(x, y, std::max(p.top(), r) + 1.5 * diameter), ok, moves);
  if (settled) *settled = ok;
  return wrapStrict(box, c);
}

Deposit deposit(const BoxDef& box, const PopulationDef& population, const DepositionDef& def, std::uint64_t seed,
                const ProgressFn& progress) {
  const auto start = std::chrono::steady_clock::now();
  box.validate();
  population.validate();
  def.validate();

  Deposit out;
  out.placeholderDiameter = population.maxCircumscribedDiameter();
  // Grains first: their number is the number of placeholders.
  out.grains = def.grainCount > 0
                   ? drawGrainCount(population, def.grainCount, seed)
                   : drawGrains(population, def.expectedSolidFraction * box.lengthX * box.width * box.height, seed);
  if (out.grains.empty())
    throw std::invalid_argument(fmt::format(
        "deposition: a box of {} x {} x {} at expected_solid_fraction {} holds no grain; raise height or grain_count",
        box.lengthX, box.width, box.height, def.expectedSolidFraction));

  Rng xy(seed, StreamId::DepositionXY);
  PlaceholderPile pile = depositPlaceholders(box, out.placeholderDiameter, out.grains.size(), xy, progress);
  out.placeholders = std::move(pile.centres);
  out.unsettledCount = pile.unsettledCount;
  out.meanMoves = pile.meanMoves;

  // Substitution: Fisher-Yates shuffle of the grains, then grain i takes placeholder i.
  Rng order(seed, StreamId::GrainOrder);
  for (std::size_t i = out.grains.size() - 1; i > 0; --i)
    std::swap(out.grains[i], out.grains[static_cast<std::size_t>(order.below(i + 1))]);
  double top = 0.0;
  for (std::size_t i = 0; i < out.grains.size(); ++i) {
    out.grains[i].position = out.placeholders[i];
    top = std::max(top, out.placeholders[i].z());
  }

  const double d = out.placeholderDiameter;
  out.pileHeight = top + 0.5 * d;
  const double boxVolume = box.lengthX * box.width * out.pileHeight;
  out.placeholderSolidFraction =
      static_cast<double>(out.placeholders.size()) * std::numbers::pi / 6.0 * d * d * d / boxVolume;
  out.solidFraction = totalVolume(out.grains) / boxVolume;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace confpack::compaction
