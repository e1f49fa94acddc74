// Geometric deposition (docs/model.md, "Deposition"). Analytic seats for hand-built piles, then
// random piles checked from their final geometry alone by brute force (no code shared with the
// deposition): overlaps, stability on three earlier supports or the floor, box bounds,
// reproducibility, and the grain bookkeeping of the substitution.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <tuple>
#include <vector>

#include "compaction/deposition.hpp"

using namespace confpack::core;
using namespace confpack::compaction;

namespace {

constexpr double kD = 1.1;  // placeholder diameter of a monodisperse sphere population [d_L]
constexpr double kR = 0.5 * kD;

BoxDef makeBox(double lx, double w, bool periodicY, double h = 6.0) {
  BoxDef b;
  b.lengthX = lx;
  b.width = w;
  b.periodicY = periodicY;
  b.height = h;
  return b;
}

struct PileCheck {
  double maxOverlap = 0.0;   // [D]
  std::size_t unstable = 0;  // placeholders neither on the floor nor on a stable triple
  std::size_t onFloor = 0;
  std::size_t onWall = 0;     // placeholders with a side wall among their contacts
  std::size_t wallSeats = 0;  // seated on a triple that includes a side wall
  std::size_t outside = 0;    // placeholders outside the box
  // Centres between 1e-9 D and 1e-4 D from a wall plane y = D/2 (or W - D/2): a placeholder
  // that slid down a wall must sit on it exactly; a free one lands that close with odds ~1e-4.
  std::size_t wallNearMiss = 0;
};

// A support of placeholder i found from the final geometry: earlier placeholders within 1e-9 D
// of contact (any periodic image), the floor (z = D/2) and the side walls (y = D/2, W - D/2).
struct Contact {
  bool sphere = false;
  Vec3 normal;  // unit, from the support towards the placeholder
  Vec3 centre;  // support centre image (spheres)
};

// Stability of a frictionless sphere on three supports under gravity.
// - three spheres: the centre's horizontal projection lies inside the triangle of the supports'
//   projections (equivalently of the contact points, which form the half-size homothetic
//   triangle around the centre), and the centre lies above the plane through the three support
//   centres. One support may be a little above the centre (an overhang pushing sideways and
//   down): that seat is still in equilibrium. Indeed e_z = sum lambda_k (c - c_k)/D with
//   lambda >= 0 gives, horizontally, c_h = sum mu_k c_k,h (mu = lambda / sum lambda: inside the
//   triangle) and, vertically, z_c - sum mu_k z_k = D / sum lambda > 0 (above the plane); and
//   conversely.
// - a triple with a side wall: the wall pushes horizontally, so the check is the force balance
//   itself: e_z = sum lambda_i n_i must have a solution with every lambda_i >= 0 (support
//   forces are compressive).
bool stableTriple(const Vec3& c, const Contact& a, const Contact& b, const Contact& d) {
  const double tol = 1e-9;
  if (a.sphere && b.sphere && d.sphere) {
    // Barycentric coordinates of c_xy in the triangle (a, b, d).
    const double x1 = a.centre.x(), y1 = a.centre.y(), x2 = b.centre.x(), y2 = b.centre.y();
    const double x3 = d.centre.x(), y3 = d.centre.y();
    const double det = (y2 - y3) * (x1 - x3) + (x3 - x2) * (y1 - y3);
    if (std::abs(det) < 1e-12) return false;
    const double l1 = ((y2 - y3) * (c.x() - x3) + (x3 - x2) * (c.y() - y3)) / det;
    const double l2 = ((y3 - y1) * (c.x() - x3) + (x1 - x3) * (c.y() - y3)) / det;
    const double l3 = 1.0 - l1 - l2;
    const double planeZ = l1 * a.centre.z() + l2 * b.centre.z() + l3 * d.centre.z();
    return l1 >= -tol && l2 >= -tol && l3 >= -tol && c.z() > planeZ;
  }
  Mat3 n;
  n << a.normal, b.normal, d.normal;
  if (std::abs(n.determinant()) < 1e-9) return false;
  const Vec3 lambda = n.inverse() * Vec3::UnitZ();
  return (lambda.array() >= -tol).all();
}

PileCheck checkPile(const BoxDef& box, double dia, const std::vector<Vec3>& c) {
  PileCheck out;
  const double tol = 1e-9 * dia;
  const double r = 0.5 * dia;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Vec3& p = c[i];
    if (p.x() < 0.0 || p.x() >= box.lengthX || p.z() < r - tol) ++out.outside;
    if (box.periodicY ? (p.y() < 0.0 || p.y() >= box.width) : (p.y() < r - tol || p.y() > box.width - r + tol))
      ++out.outside;
    std::vector<Contact> contacts;
    // Every image within two periods, not only the minimum image: with a period below 2 D a
    // placeholder can touch several images of one sphere (or of itself).
    const int ky = box.periodicY ? 2 : 0;
    for (std::size_t j = 0; j < c.size(); ++j)
      for (int sx = -2; sx <= 2; ++sx)
        for (int sy = -ky; sy <= ky; ++sy) {
          if (j == i && sx == 0 && sy == 0) continue;
          const Vec3 sep = p - c[j] - Vec3(sx * box.lengthX, sy * box.width, 0.0);
          const double dist = sep.norm();
          out.maxOverlap = std::max(out.maxOverlap, (dia - dist) / dia);
          if (j < i && std::abs(dist - dia) < tol) contacts.push_back({true, sep / dist, p - sep});
        }
    const bool floor = std::abs(p.z() - r) < tol;
    if (floor) ++out.onFloor;
    if (!box.periodicY) {
      const bool low = std::abs(p.y() - r) < tol, high = std::abs(box.width - r - p.y()) < tol;
      if (low) contacts.push_back({false, Vec3::UnitY(), Vec3::Zero()});
      if (high) contacts.push_back({false, -Vec3::UnitY(), Vec3::Zero()});
      if (low || high) ++out.onWall;
      const double toWall = std::min(std::abs(p.y() - r), std::abs(box.width - r - p.y()));
      if (toWall >= tol && toWall < 1e-4 * dia) ++out.wallNearMiss;
    }
    bool stable = floor;
    bool wallSeat = false;
    for (std::size_t a = 0; a < contacts.size() && !stable; ++a)
      for (std::size_t b = a + 1; b < contacts.size() && !stable; ++b)
        for (std::size_t d = b + 1; d < contacts.size() && !stable; ++d)
          if (stableTriple(p, contacts[a], contacts[b], contacts[d])) {
            stable = true;
            wallSeat = !(contacts[a].sphere && contacts[b].sphere && contacts[d].sphere);
          }
    if (!stable) ++out.unstable;
    if (wallSeat) ++out.wallSeats;
  }
  return out;
}

// Exact volume of a sphere of radius r whose lowest point is at height b, below height z.
double capBelow(double r, double b, double z) {
  const double h = std::clamp(z - b, 0.0, 2.0 * r);
  return std::numbers::pi * h * h * (3.0 * r - h) / 3.0;
}

}  // namespace

TEST_CASE("a placeholder on an empty floor lands at z = D/2 under its drop point", "[core][deposition]") {
  const BoxDef box = makeBox(8.0, 6.0, false);
  bool settled = false;
  const Vec3 c = dropPlaceholder(box, kD, {}, 2.5, 3.1, &settled);
  CHECK(settled);
  CHECK(c.x() == 2.5);
  CHECK(c.y() == 3.1);
  CHECK(c.z() == Approx(kR).margin(1e-12));
}

TEST_CASE("a placeholder dropped on one floor sphere rolls off it to the floor, at distance D", "[core][deposition]") {
  const BoxDef box = makeBox(8.0, 6.0, false);
  const Vec3 s(4.0, 3.0, kR);
  const Vec3 c = dropPlaceholder(box, kD, {s}, 4.3, 3.2);
  // Steepest descent over a sphere stays in the vertical plane through the drop direction.
  const Vec3 dir = Vec3(0.3, 0.2, 0.0).normalized();
  const Vec3 expected = s + kD * dir;
  CHECK((c - expected).norm() < 1e-9);
}

TEST_CASE("three floor spheres in a triangle seat the next one at the tetrahedral height", "[core][deposition]") {
  const BoxDef box = makeBox(8.0, 6.0, false);
  const std::vector<Vec3> pile = {Vec3(3.0, 2.5, kR), Vec3(3.0 + kD, 2.5, kR),
                                  Vec3(3.0 + 0.5 * kD, 2.5 + 0.5 * std::sqrt(3.0) * kD, kR)};
  const Vec3 centroid = (pile[0] + pile[1] + pile[2]) / 3.0;
  // Off-centre drops land on one sphere, roll into a groove, then into the pocket.
  for (const Vec3& off : {Vec3(0.0, 0.0, 0.0), Vec3(0.07, -0.04, 0.0), Vec3(-0.2, 0.15, 0.0)}) {
    bool settled = false;
    const Vec3 c = dropPlaceholder(box, kD, pile, centroid.x() + off.x(), centroid.y() + off.y(), &settled);
    CHECK(settled);
    CHECK(c.x() == Approx(centroid.x()).margin(1e-9));
    CHECK(c.y() == Approx(centroid.y()).margin(1e-9));
    CHECK(c.z() == Approx(kR + kD * std::sqrt(2.0 / 3.0)).margin(1e-9));
  }
}

TEST_CASE("a groove too wide to hold a placeholder lets it roll down to the floor between the spheres",
          "[core][deposition]") {
  // Two floor spheres 1.5 D apart: the groove circle |c - c_j| = |c - c_k| = D has a horizontal
  // axis, so the upper-sphere release height is the axis height D/2: the placeholder reaches the
  // floor at a distance D sqrt(1 - (3/4)^2) = D sqrt(7)/4 from the axis.
  const BoxDef box = makeBox(8.0, 6.0, false);
  const std::vector<Vec3> pile = {Vec3(3.0, 3.0, kR), Vec3(3.0 + 1.5 * kD, 3.0, kR)};
  const Vec3 c = dropPlaceholder(box, kD, pile, 3.0 + 0.75 * kD, 3.1);
  CHECK(c.x() == Approx(3.0 + 0.75 * kD).margin(1e-9));
  CHECK(c.y() == Approx(3.0 + kD * std::sqrt(7.0) / 4.0).margin(1e-9));
  CHECK(c.z() == Approx(kR).margin(1e-9));
}

TEST_CASE("a side wall is a support: rolling along it and seating against it", "[core][deposition]") {
  const BoxDef box = makeBox(8.0, 6.0, false);
  SECTION("rolling off a sphere towards the wall, then along the wall to the floor") {
    // The sphere is 0.3 from the wall plane y = D/2 of centres; the placeholder meets the wall,
    // then follows the circle (sphere) x (plane y = D/2) of radius sqrt(D^2 - 0.3^2) to the floor.
    const Vec3 s(4.0, kR + 0.3, kR);
    const Vec3 c = dropPlaceholder(box, kD, {s}, 4.2, kR);
    CHECK(c.y() == Approx(kR).margin(1e-12));
    CHECK(c.z() == Approx(kR).margin(1e-9));
    CHECK(c.x() == Approx(4.0 + std::sqrt(kD * kD - 0.09)).margin(1e-9));
  }
  SECTION("seated on two spheres and the wall") {
    // Supports 1.2 D apart along x, 0.4 from the wall plane: the seat is on the wall, midway,
    // at |c - c_j| = D: z = D/2 + sqrt(D^2 - (0.6 D)^2 - 0.4^2).
    const std::vector<Vec3> pile = {Vec3(3.0, kR + 0.4, kR), Vec3(3.0 + 1.2 * kD, kR + 0.4, kR)};
    bool settled = false;
    const Vec3 c = dropPlaceholder(box, kD, pile, 3.0 + 0.6 * kD + 0.03, kR + 0.1, &settled);
    CHECK(settled);
    CHECK(c.x() == Approx(3.0 + 0.6 * kD).margin(1e-9));
    CHECK(c.y() == Approx(kR).margin(1e-12));
    CHECK(c.z() == Approx(kR + std::sqrt(kD * kD * 0.64 - 0.16)).margin(1e-9));
    const PileCheck check = checkPile(box, kD, {pile[0], pile[1], c});
    CHECK(check.unstable == 0);
    CHECK(check.wallSeats == 1);
  }
}

TEST_CASE("periodic images are supports across the x boundary", "[core][deposition]") {
  // A floor sphere at x = 0.2 and a drop at x = L_x - 0.1: the placeholder falls on the image at
  // x = L_x + 0.2 and rolls off it away from it, landing at x = L_x + 0.2 - D cos(...) wrapped.
  const BoxDef box = makeBox(8.0, 6.0, true);
  const Vec3 s(0.2, 3.0, kR);
  const Vec3 c = dropPlaceholder(box, kD, {s}, 7.9, 3.0);
  CHECK(c.x() == Approx(8.0 + 0.2 - kD).margin(1e-9));
  CHECK(c.y() == Approx(3.0).margin(1e-12));
  CHECK(c.z() == Approx(kR).margin(1e-9));
}

TEST_CASE("random placeholder piles overlap nothing and every placeholder is seated", "[core][deposition]") {
  const bool periodicY = GENERATE(false, true);
  const BoxDef box = makeBox(8.0, 6.0, periodicY);
  Rng rng(3, StreamId::DepositionXY);
  const std::size_t n = 400;
  const PlaceholderPile pile = depositPlaceholders(box, kD, n, rng);
  REQUIRE(pile.centres.size() == n);
  CHECK(pile.unsettledCount == 0);
  const PileCheck check = checkPile(box, kD, pile.centres);
  INFO("periodic y: " << periodicY << ", floor " << check.onFloor << ", wall " << check.onWall << ", mean moves "
                      << pile.meanMoves);
  CHECK(check.maxOverlap < 1e-9);
  CHECK(check.unstable == 0);
  CHECK(check.outside == 0);
  CHECK(check.wallNearMiss == 0);
  // A 8 x 6 floor holds ~20-40 placeholders in its first layer (random sequential adsorption
  // of disks of diameter D covers about 0.55 of the plane: 0.55 * 48 / (pi D^2 / 4) = 28).
  CHECK(check.onFloor >= 15);
  CHECK(check.onFloor <= 45);
  if (!periodicY) {
    CHECK(check.onWall > 0);     // the walls are used as supports...
    CHECK(check.wallSeats > 0);  // ...including in three-point seats
  }
}

TEST_CASE("degenerate boxes: a single-file channel (W = D) and a period shorter than 2 D", "[core][deposition]") {
  // Both force coincidences that random drops never produce in a wide box: in the channel every
  // placeholder touches both walls and can be pinched between two spheres at equal heights; in
  // the 1.2 x 1.2 biperiodic column each placeholder sits in a symmetric four-support pocket.
  // Seeds chosen among those that once exhausted the move budget.
  const BoxDef channel = makeBox(6.0, kD, false);
  const BoxDef column = makeBox(1.2, 1.2, true);
  for (const auto& [box, n, seed] : {std::tuple{channel, 200, 6}, std::tuple{column, 60, 1}}) {
    Rng rng(static_cast<std::uint64_t>(seed), StreamId::DepositionXY);
    const PlaceholderPile pile = depositPlaceholders(box, kD, static_cast<std::size_t>(n), rng);
    CHECK(pile.unsettledCount == 0);
    const PileCheck check = checkPile(box, kD, pile.centres);
    CHECK(check.maxOverlap < 1e-9);
    CHECK(check.unstable == 0);
    CHECK(check.outside == 0);
  }
}

TEST_CASE("the bulk of a sequential deposit has the Visscher-Bolsterli solid fraction", "[core][deposition]") {
  // Sequential deposition of equal spheres with rolling to the lowest three-point seat gives
  // phi = 0.58 in the bulk (Visscher & Bolsterli 1972: 0.582; Jodrey & Tory 1979). Measured away
  // from the floor and the free top (3 D each), periodic in x and y so that no wall layer lowers
  // it; 1200 spheres give about 25 D of pile, so the statistical spread is ~0.005.
  const BoxDef box = makeBox(8.0, 6.0, true);
  Rng rng(5, StreamId::DepositionXY);
  const PlaceholderPile pile = depositPlaceholders(box, kD, 1200, rng);
  double top = 0.0;
  for (const Vec3& c : pile.centres) top = std::max(top, c.z());
  const double z0 = 3.0 * kD, z1 = top - 3.0 * kD;
  REQUIRE(z1 > z0 + 10.0 * kD);
  double volume = 0.0;
  for (const Vec3& c : pile.centres) volume += capBelow(kR, c.z() - kR, z1) - capBelow(kR, c.z() - kR, z0);
  const double phi = volume / (box.lengthX * box.width * (z1 - z0));
  INFO("bulk phi " << phi);
  CHECK(phi > 0.56);
  CHECK(phi < 0.60);
}

TEST_CASE("deposition is reproducible bit for bit from its seed", "[core][deposition]") {
  const BoxDef box = makeBox(8.0, 6.0, false, 5.0);
  PopulationDef pop;
  pop.smallFraction = 25.0;
  const DepositionDef def;
  const Deposit a = deposit(box, pop, def, 42);
  const Deposit b = deposit(box, pop, def, 42);
  const Deposit c = deposit(box, pop, def, 43);
  REQUIRE(a.grains.size() == b.grains.size());
  bool identical = true;
  for (std::size_t i = 0; i < a.grains.size(); ++i) {
    identical = identical && a.placeholders[i] == b.placeholders[i] && a.grains[i].position == b.grains[i].position &&
                a.grains[i].size == b.grains[i].size;
  }
  CHECK(identical);
  CHECK(a.pileHeight == b.pileHeight);
  std::size_t same = 0;
  for (std::size_t i = 0; i < std::min(a.grains.size(), c.grains.size()); ++i)
    if (a.placeholders[i] == c.placeholders[i]) ++same;
  CHECK(same == 0);
}

TEST_CASE("deposit: grain count, composition, substitution and solid fractions", "[core][deposition]") {
  const BoxDef box = makeBox(8.0, 6.0, false, 6.0);
  DepositionDef def;
  def.expectedSolidFraction = 0.6;
  const double targetVolume = def.expectedSolidFraction * box.lengthX * box.width * box.height;

  SECTION("monodisperse spheres") {
    PopulationDef pop;
    const Deposit dep = deposit(box, pop, def, 7);
    // Mean volume of a sphere of size d(1 + s z), z standard normal: (pi/6) d^3 (1 + 3 s^2)
    // (truncation at 3 sigma changes it by < 1e-4). The count then follows n = V / <v>, up to
    // the draw's fluctuation ~ 3 s / sqrt(n) ~ 0.6 %.
    const double meanVolume = std::numbers::pi / 6.0 * (1.0 + 3.0 / 900.0);
    const double expected = targetVolume / meanVolume;
    CHECK(static_cast<double>(dep.grains.size()) == Approx(expected).epsilon(0.03));
    CHECK(dep.placeholderDiameter == Approx(kD));
    CHECK(dep.unsettledCount == 0);
    // Substitution: grain i sits on placeholder i.
    for (std::size_t i = 0; i < dep.grains.size(); ++i) REQUIRE(dep.grains[i].position == dep.placeholders[i]);
    // Heights and fractions are consistent with the geometry.
    double top = 0.0;
    for (const Vec3& c : dep.placeholders) top = std::max(top, c.z());
    CHECK(dep.pileHeight == Approx(top + 0.5 * kD));
    const double boxVolume = box.lengthX * box.width * dep.pileHeight;
    CHECK(dep.placeholderSolidFraction ==
          Approx(static_cast<double>(dep.grains.size()) * std::numbers::pi / 6.0 * kD * kD * kD / boxVolume));
    CHECK(dep.solidFraction == Approx(totalVolume(dep.grains) / boxVolume));
    // Plausible range of the placeholder fraction of the whole deposit. The bulk is 0.58 (test
    // above); the walls cost a layer of lower density (phi(W) = phi_bulk - C/W; this deposit
    // gives phi = 0.570 at W = 20 and 0.559 at W = 10, C ~ 0.24: ~ -0.04 at W = 6), and
    // pileHeight counts the rough top (about one D above the mean surface of a pile ~ 9 D
    // high: -10 %). Hence 0.42 to 0.56.
    INFO("placeholder fraction " << dep.placeholderSolidFraction << " pile height " << dep.pileHeight);
    CHECK(dep.placeholderSolidFraction > 0.42);
    CHECK(dep.placeholderSolidFraction < 0.56);
    // Real grains are smaller than the placeholders: <v> / v_D = (1 + 3/900) / 1.1^3 = 0.754.
    CHECK(dep.solidFraction / dep.placeholderSolidFraction ==
          Approx((1.0 + 3.0 / 900.0) / (kD * kD * kD)).epsilon(0.01));
    const PileCheck check = checkPile(box, kD, dep.placeholders);
    CHECK(check.maxOverlap < 1e-9);
    CHECK(check.unstable == 0);
  }

  SECTION("bidisperse spheres, x_S = 25 %") {
    PopulationDef pop;
    pop.smallFraction = 25.0;
    const Deposit dep = deposit(box, pop, def, 8);
    double small = 0.0, total = 0.0, largest = 0.0;
    std::size_t nSmall = 0;
    for (const Grain& g : dep.grains) {
      total += g.volume();
      largest = std::max(largest, g.volume());
      if (g.size < 0.75) {
        small += g.volume();
        ++nSmall;
      }
    }
    // Each population stops at the grain count closest to its share: within one grain volume.
    CHECK(small / total == Approx(0.25).margin(largest / total));
    CHECK(total == Approx(targetVolume).margin(2.0 * largest));
    // n = V (1 - x) / <v_L> + V x / <v_S>, with <v_S> = <v_L> / 8.
    const double vL = std::numbers::pi / 6.0 * (1.0 + 3.0 / 900.0);
    const double expected = targetVolume * (0.75 / vL + 0.25 * 8.0 / vL);
    CHECK(static_cast<double>(dep.grains.size()) == Approx(expected).epsilon(0.03));
    // The placeholders all circumscribe the largest possible grain, whatever the mix.
    CHECK(dep.placeholderDiameter == Approx(kD));
    // The shuffle mixes the populations along the pile (drawGrains lists large ones first).
    std::size_t smallInFirstHalf = 0;
    for (std::size_t i = 0; i < dep.grains.size() / 2; ++i)
      if (dep.grains[i].size < 0.75) ++smallInFirstHalf;
    CHECK(smallInFirstHalf > nSmall / 4);
    CHECK(smallInFirstHalf < 3 * nSmall / 4);
  }

  SECTION("a fixed grain count") {
    PopulationDef pop;
    pop.smallFraction = 40.0;
    def.grainCount = 250;
    const Deposit dep = deposit(box, pop, def, 9);
    REQUIRE(dep.grains.size() == 250);
    double small = 0.0, total = 0.0;
    for (const Grain& g : dep.grains) {
      total += g.volume();
      if (g.size < 0.75) small += g.volume();
    }
    // 250 grains at x_S = 40 %: n_S = 250 * (0.4 * 8) / (0.6 + 0.4 * 8) = 210.5 -> 211 small.
    CHECK(small / total == Approx(0.40).margin(0.03));
  }
}

TEST_CASE("pinacoids keep the sizes and orientations they were drawn with", "[core][deposition]") {
  const BoxDef box = makeBox(8.0, 6.0, true, 4.0);
  PopulationDef pop;
  pop.shape = ShapeKind::Pinacoid;
  const DepositionDef def;
  const Deposit dep = deposit(box, pop, def, 4);
  auto drawn = drawGrains(pop, def.expectedSolidFraction * box.lengthX * box.width * box.height, 4);
  REQUIRE(dep.grains.size() == drawn.size());
  CHECK(dep.placeholderDiameter == Approx(pop.maxCircumscribedDiameter()));
  auto key = [](const Grain& g) {
    return std::array<double, 5>{g.size, g.orientation.w(), g.orientation.x(), g.orientation.y(), g.orientation.z()};
  };
  std::vector<std::array<double, 5>> a, b;
  for (const Grain& g : dep.grains) a.push_back(key(g));
  for (const Grain& g : drawn) b.push_back(key(g));
  CHECK(a != b);  // the order was shuffled...
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  CHECK(a == b);  // ...but the grains are the same, bit for bit
  const PileCheck check = checkPile(box, dep.placeholderDiameter, dep.placeholders);
  CHECK(check.maxOverlap < 1e-9);
  CHECK(check.unstable == 0);
}

TEST_CASE("deposition reports progress at least every 1 % and at the end", "[core][deposition]") {
  const BoxDef box = makeBox(8.0, 6.0, false);
  Rng rng(1, StreamId::DepositionXY);
  std::vector<std::size_t> done;
  const std::size_t n = 500;
  depositPlaceholders(box, kD, n, rng, [&](std::size_t k, std::size_t total) {
    REQUIRE(total == n);
    done.push_back(k);
  });
  REQUIRE(!done.empty());
  CHECK(done.back() == n);
  std::size_t previous = 0;
  for (std::size_t k : done) {
    CHECK(k > previous);
    CHECK(k - previous <= n / 100);
    previous = k;
  }
}

TEST_CASE("deposition settings: JSON round trip and refusal of bad input", "[core][deposition]") {
  DepositionDef d;
  d.expectedSolidFraction = 0.62;
  d.grainCount = 1234;
  nlohmann::json j = d;
  CHECK(j.at("expected_solid_fraction") == 0.62);
  CHECK(j.at("grain_count") == 1234);
  const auto back = j.get<DepositionDef>();
  CHECK(back.expectedSolidFraction == d.expectedSolidFraction);
  CHECK(back.grainCount == d.grainCount);
  CHECK(nlohmann::json::object().get<DepositionDef>().expectedSolidFraction == DepositionDef{}.expectedSolidFraction);

  CHECK_THROWS_AS(nlohmann::json({{"grain_count", -5}}).get<DepositionDef>(), std::invalid_argument);
  CHECK_THROWS_AS(nlohmann::json({{"grain_count", 2.5}}).get<DepositionDef>(), std::invalid_argument);
  CHECK_THROWS_AS(nlohmann::json({{"expected_solid_fraction", "high"}}).get<DepositionDef>(), std::invalid_argument);

  const PopulationDef pop;
  DepositionDef bad;
  bad.expectedSolidFraction = 0.0;
  CHECK_THROWS_AS(deposit(makeBox(8.0, 6.0, false), pop, bad, 1), std::invalid_argument);
  bad.expectedSolidFraction = 1.5;
  CHECK_THROWS_AS(deposit(makeBox(8.0, 6.0, false), pop, bad, 1), std::invalid_argument);
  // A gap narrower than the placeholder, and a box that holds no grain.
  CHECK_THROWS_AS(deposit(makeBox(8.0, 1.0, false), pop, DepositionDef{}, 1), std::invalid_argument);
  CHECK_THROWS_AS(deposit(makeBox(8.0, 6.0, false, 1e-4), pop, DepositionDef{}, 1), std::invalid_argument);
  CHECK_THROWS_AS(dropPlaceholder(makeBox(8.0, 6.0, false), kD, {}, 1.0, 0.1), std::invalid_argument);
}

TEST_CASE("30,400 placeholders deposit in well under 30 s", "[.perf][core][deposition]") {
  // The largest sphere sample of the paper (x_S = 40, h = 16-20), as placeholders of diameter 1.1.
  const BoxDef box = makeBox(20.0, 20.0, false);
  Rng rng(1, StreamId::DepositionXY);
  const auto start = std::chrono::steady_clock::now();
  const PlaceholderPile pile = depositPlaceholders(box, kD, 30400, rng);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WARN("30400 placeholders: " << seconds << " s, mean moves " << pile.meanMoves << ", unsettled "
                              << pile.unsettledCount);
  CHECK(seconds < 30.0);
  CHECK(pile.unsettledCount == 0);
}
