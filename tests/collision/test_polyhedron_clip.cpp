// Exact clipped and intersection volumes (collision/polyhedron_clip): analytic answers only.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "collision/polyhedron_clip.hpp"
#include "core/pinacoid.hpp"
#include "tests/support/polyhedra.hpp"

using namespace confpack::core;
using namespace confpack::collision;
using namespace confpack::testing;

namespace {

ConvexPolyhedron makeCuboid(double sx, double sy, double sz) {
  const double a = sx / 2, b = sy / 2, c = sz / 2;
  std::vector<Vec3> v = {{-a, -b, -c}, {a, -b, -c}, {a, b, -c}, {-a, b, -c},
                         {-a, -b, c},  {a, -b, c},  {a, b, c},  {-a, b, c}};
  std::vector<std::vector<int>> f = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                     {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};
  return ConvexPolyhedron(std::move(v), std::move(f));
}

}  // namespace

TEST_CASE("clip: unclipped polytope has the polyhedron's volume") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{});
  const double v = pinacoidMassProperties(1.0, PinacoidParams{}).volume;
  std::mt19937_64 rng(3);
  const PlacedPolyhedron placed{&p, Vec3(3.0, -2.0, 7.0), randomRotation(rng)};
  CHECK(toPolytope(placed).volume() == Approx(v).epsilon(1e-13));
  CHECK(clippedVolume(placed, {}) == Approx(v).epsilon(1e-13));
}

TEST_CASE("clip: any plane through the centre of a pinacoid halves it (central symmetry)") {
  // Three mirror planes make the pinacoid centrally symmetric, so every plane through the
  // centroid cuts it into two congruent halves: V/2, whatever the plane and the pose.
  const PinacoidParams params{0.8, 0.7, 55.0};
  const ConvexPolyhedron p = makePinacoid(1.2, params);
  const double v = pinacoidMassProperties(1.2, params).volume;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 c(g(rng), g(rng), g(rng));
    const PlacedPolyhedron placed{&p, c, randomRotation(rng)};
    const Vec3 n = Vec3(g(rng), g(rng), g(rng)).normalized();
    const Plane lower[1] = {{n, n.dot(c)}};
    const Plane upper[1] = {{-n, -n.dot(c)}};
    CHECK(clippedVolume(placed, lower) == Approx(v / 2).epsilon(1e-12));
    CHECK(clippedVolume(placed, upper) == Approx(v / 2).epsilon(1e-12));
  }
  // The mid-plane itself passes exactly through the 4 rectangle vertices.
  const PlacedPolyhedron flat{&p, Vec3::Zero(), Mat3::Identity()};
  const Plane mid[1] = {{Vec3::UnitZ(), 0.0}};
  CHECK(clippedVolume(flat, mid) == Approx(v / 2).epsilon(1e-13));
}

TEST_CASE("clip: planes exactly through vertices and edges give the analytic pieces") {
  const PinacoidParams params{};
  const double L = 1.0;
  const ConvexPolyhedron p = makePinacoid(L, params);
  const double l = pinacoidRidgeHalfLength(L, params);
  const double G = 1.0, E = 1.0;
  const double v = pinacoidMassProperties(L, params).volume;
  const PlacedPolyhedron placed{&p, Vec3::Zero(), Mat3::Identity()};
  // For |x| <= l every cross-section is the rhombus (+-G/2, 0), (0, +-E/2) of area G E / 2, so
  // the middle prism holds l G E and each end (x >= l, through the ridge ends) E G (L - 2l) / 6.
  const Plane endCut[1] = {{-Vec3::UnitX(), -l}};  // keeps x >= l: plane through vertices 4 and 6
  CHECK(clippedVolume(placed, endCut) == Approx(E * G * (L - 2 * l) / 6).epsilon(1e-13));
  CHECK(slabVolume(placed, 0, -l, l) == Approx(l * G * E).epsilon(1e-13));
  // A plane touching the body along the edge x = L/2 keeps everything or nothing.
  const Plane touchKeep[1] = {{Vec3::UnitX(), 0.5 * L}};
  const Plane touchDrop[1] = {{-Vec3::UnitX(), -0.5 * L}};
  CHECK(clippedVolume(placed, touchKeep) == Approx(v).epsilon(1e-14));
  CHECK(clippedVolume(placed, touchDrop) == 0.0);
  // A plane through the top ridge only (z = E/2) likewise.
  const Plane ridge[1] = {{-Vec3::UnitZ(), -0.5 * E}};
  CHECK(clippedVolume(placed, ridge) == 0.0);

  // Unit cube: x + y + z <= 1 passes through 3 vertices (corner tetrahedron 1/6);
  // x + y <= 1 passes through a diagonal pair of edges (half the cube).
  const ConvexPolyhedron cube = makeCuboid(1, 1, 1);
  const PlacedPolyhedron c{&cube, Vec3(0.5, 0.5, 0.5), Mat3::Identity()};
  const Plane corner[1] = {{Vec3(1, 1, 1), 1.0}};
  CHECK(clippedVolume(c, corner) == Approx(1.0 / 6.0).epsilon(1e-14));
  const Plane diagonal[1] = {{Vec3(1, 1, 0), 1.0}};
  CHECK(clippedVolume(c, diagonal) == Approx(0.5).epsilon(1e-14));
  // Successive cuts through the same vertices leave a consistent closed polytope.
  const Plane both[2] = {{Vec3(1, 1, 0), 1.0}, {Vec3(1, 1, 1), 1.0}};
  CHECK(clippedVolume(c, both) == Approx(1.0 / 6.0).epsilon(1e-14));
  const Plane cutThenCorner[3] = {{Vec3(1, 0, 0), 0.5}, {Vec3(0, 1, 0), 0.5}, {Vec3(0, 0, 1), 0.5}};
  CHECK(clippedVolume(c, cutThenCorner) == Approx(0.125).epsilon(1e-14));
}

TEST_CASE("clip: slab volumes over a partition of z sum to the volume") {
  const PinacoidParams params{0.9, 0.8, 62.0};
  const ConvexPolyhedron p = makePinacoid(1.1, params);
  const double v = pinacoidMassProperties(1.1, params).volume;
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    const PlacedPolyhedron placed{&p, Vec3(0.1 * trial, 2.0, 5.0 + 0.37 * trial), randomRotation(rng)};
    std::vector<double> edges;
    for (double z = 4.0; z <= 9.0 + 1e-9; z += 0.02) edges.push_back(z);  // thin slices, d_L/50
    double sum = 0.0;
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) sum += slabVolume(placed, 2, edges[i], edges[i + 1]);
    CHECK(sum == Approx(v).epsilon(1e-12));
    // The one-sweep version gives the same slab by slab.
    const std::vector<double> sweep = slabVolumes(placed, 2, edges);
    REQUIRE(sweep.size() == edges.size() - 1);
    double sweepSum = 0.0;
    for (std::size_t i = 0; i < sweep.size(); ++i) {
      CHECK(sweep[i] == Approx(slabVolume(placed, 2, edges[i], edges[i + 1])).margin(1e-14));
      sweepSum += sweep[i];
    }
    CHECK(sweepSum == Approx(v).epsilon(1e-12));
  }
}

TEST_CASE("clip: box volume of a cuboid equals the analytic overlap box") {
  const ConvexPolyhedron cube = makeCuboid(1.0, 0.6, 0.8);
  const PlacedPolyhedron c{&cube, Vec3(0.2, -0.1, 0.3), Mat3::Identity()};  // [-0.3,0.7]x[-0.4,0.2]x[-0.1,0.7]
  auto overlap = [](double lo1, double hi1, double lo2, double hi2) {
    return std::max(0.0, std::min(hi1, hi2) - std::max(lo1, lo2));
  };
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    Vec3 lo(u(rng), u(rng), u(rng));
    const Vec3 hi = lo + Vec3(0.5 + 0.5 * (u(rng) + 1), 0.3 + 0.5 * (u(rng) + 1), 0.2 + 0.5 * (u(rng) + 1));
    const double expected =
        overlap(-0.3, 0.7, lo.x(), hi.x()) * overlap(-0.4, 0.2, lo.y(), hi.y()) * overlap(-0.1, 0.7, lo.z(), hi.z());
    CHECK(boxVolume(c, lo, hi) == Approx(expected).margin(1e-14));
  }
  // Box faces coinciding with the cuboid faces (degenerate planes through whole faces).
  CHECK(boxVolume(c, Vec3(-0.3, -0.4, -0.1), Vec3(0.7, 0.2, 0.7)) == Approx(0.48).epsilon(1e-14));
  CHECK(boxVolume(c, Vec3(0.7, -0.4, -0.1), Vec3(1.7, 0.2, 0.7)) == 0.0);
}

TEST_CASE("clip: intersection volumes of known pairs") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{});
  const double v = pinacoidMassProperties(1.0, PinacoidParams{}).volume;
  std::mt19937_64 rng(21);
  const Mat3 r = randomRotation(rng);
  const PlacedPolyhedron a{&p, Vec3(1, 2, 3), r};
  CHECK(intersectionVolume(a, a) == Approx(v).epsilon(1e-12));  // every face plane cuts through faces

  const ConvexPolyhedron cube = makeCuboid(1, 1, 1);
  const PlacedPolyhedron c1{&cube, Vec3::Zero(), Mat3::Identity()};
  const PlacedPolyhedron c2{&cube, Vec3(0.3, 0.2, 0.1), Mat3::Identity()};
  CHECK(intersectionVolume(c1, c2) == Approx(0.7 * 0.8 * 0.9).epsilon(1e-14));
  CHECK(intersectionVolume(c2, c1) == Approx(0.7 * 0.8 * 0.9).epsilon(1e-14));
  // Far apart and face-touching pairs have no common volume.
  const PlacedPolyhedron c3{&cube, Vec3(1.0, 0.2, 0.1), Mat3::Identity()};
  CHECK(intersectionVolume(c1, c3) == 0.0);
  const PlacedPolyhedron c4{&cube, Vec3(5.0, 0.0, 0.0), Mat3::Identity()};
  CHECK(intersectionVolume(c1, c4) == 0.0);
  // A cube rotated 45 degrees about z inside a larger cube: the octagonal prism of a square
  // cut by the unit square... here simply the full cube when it fits: a 0.5-cube rotated
  // inside the unit cube.
  const ConvexPolyhedron small = makeCuboid(0.5, 0.5, 0.5);
  const PlacedPolyhedron s{&small, Vec3::Zero(), Eigen::AngleAxisd(0.785398, Vec3::UnitZ()).toRotationMatrix()};
  CHECK(intersectionVolume(c1, s) == Approx(0.125).epsilon(1e-13));
}

TEST_CASE("clip: intersection of a random pinacoid pair agrees with Monte Carlo") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{});
  std::mt19937_64 rng(77);
  const PlacedPolyhedron a{&p, Vec3::Zero(), randomRotation(rng)};
  const PlacedPolyhedron b{&p, Vec3(0.35, -0.2, 0.25), randomRotation(rng)};
  const double exact = intersectionVolume(a, b);
  REQUIRE(exact > 0.02);
  // Uniform samples in a's bounding cube; a hit is inside both bodies.
  const double R = p.boundingRadius();
  std::uniform_real_distribution<double> u(-R, R);
  const int n = 400000;
  int hits = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 x(u(rng), u(rng), u(rng));
    if (p.contains(a.rotation.transpose() * (x - a.position)) && p.contains(b.rotation.transpose() * (x - b.position)))
      ++hits;
  }
  const double box = 8 * R * R * R;
  const double frac = static_cast<double>(hits) / n;
  const double estimate = frac * box;
  const double sigma = std::sqrt(frac * (1 - frac) / n) * box;
  CHECK(std::abs(estimate - exact) < 4 * sigma);
}

TEST_CASE("clip: lattice cells partition the grain and match boxVolume") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{});
  const double v = pinacoidMassProperties(1.0, PinacoidParams{}).volume;
  std::mt19937_64 rng(4);
  const PlacedPolyhedron placed{&p, Vec3(3.01, 4.5, 2.2), randomRotation(rng)};
  const Vec3 origin(0.0, 0.0, 0.0);
  const double h = 1.0 / 20.0;
  double sum = 0.0;
  int cells = 0;
  int checked = 0;
  forEachCellVolume(placed, origin, h, [&](int i, int j, int k, double vol) {
    sum += vol;
    ++cells;
    CHECK(vol <= h * h * h * (1 + 1e-12));
    if ((i + j + k) % 37 == 0) {  // spot-check against an independent 6-plane clip
      const Vec3 lo = origin + h * Vec3(i, j, k);
      CHECK(vol == Approx(boxVolume(placed, lo, lo + Vec3::Constant(h))).margin(1e-15));
      ++checked;
    }
  });
  CHECK(sum == Approx(v).epsilon(1e-12));
  CHECK(cells > 3000);  // V / h^3 = 3789 full cells' worth, plus the cut ones
  CHECK(checked > 50);
  // Also with cell boundaries running exactly through vertices (grain at a lattice node).
  const PlacedPolyhedron aligned{&p, Vec3(1.0, 1.0, 1.0), Mat3::Identity()};
  double alignedSum = 0.0;
  forEachCellVolume(aligned, origin, 0.25, [&](int, int, int, double vol) { alignedSum += vol; });
  CHECK(alignedSum == Approx(v).epsilon(1e-13));
}

TEST_CASE("clip: bad input is refused with a clear message") {
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{});
  const PlacedPolyhedron placed{&p, Vec3::Zero(), Mat3::Identity()};
  CHECK_THROWS_AS(slabVolume(placed, 3, 0.0, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(forEachCellVolume(placed, Vec3::Zero(), 0.0, [](int, int, int, double) {}), std::invalid_argument);
  const double bad[3] = {0.0, 0.5, 0.2};
  CHECK_THROWS_AS(slabVolumes(placed, 2, bad), std::invalid_argument);
  const PlacedPolyhedron none{};
  CHECK_THROWS_AS(toPolytope(none), std::invalid_argument);
  CHECK(slabVolume(placed, 2, 0.3, 0.1) == 0.0);  // empty slab, not an error
}

TEST_CASE("clip: the two sides of any plane add up to the volume, also through vertices") {
  // Planes through 0, 1, 2 or 3 vertices of a randomly placed pinacoid, and planes a hair
  // (1e-13, inside the on-plane tolerance, or 1e-9, outside it) away from a vertex: the two
  // half-space volumes must always sum to V and each stay in [0, V].
  const ConvexPolyhedron p = makePinacoid(1.0, PinacoidParams{});
  const double v = pinacoidMassProperties(1.0, PinacoidParams{}).volume;
  std::mt19937_64 rng(31);
  std::normal_distribution<double> g;
  std::uniform_int_distribution<int> pick(0, 7);
  for (int trial = 0; trial < 2000; ++trial) {
    const Mat3 r = trial % 4 == 0 ? Mat3::Identity() : randomRotation(rng);
    const PlacedPolyhedron placed{&p, Vec3(g(rng), g(rng), 5 + g(rng)), r};
    const std::vector<Vec3> w = placed.worldVertices();
    Vec3 n = Vec3(g(rng), g(rng), g(rng)).normalized();
    Vec3 through = placed.position + 0.3 * Vec3(g(rng), g(rng), g(rng));
    switch (trial % 5) {
      case 1:
        through = w[pick(rng)];
        break;
      case 2: {  // through two vertices
        const int i = pick(rng), j = (i + 1 + pick(rng) % 7) % 8;
        through = w[i];
        n = (w[j] - w[i]).cross(Vec3(g(rng), g(rng), g(rng))).normalized();
        break;
      }
      case 3: {  // through three vertices (often a face plane or a diagonal section)
        const int i = pick(rng), j = (i + 1 + pick(rng) % 7) % 8;
        int k = pick(rng);
        while (k == i || k == j) k = pick(rng);
        const Vec3 c = (w[j] - w[i]).cross(w[k] - w[i]);
        if (c.norm() < 1e-6) continue;
        through = w[i];
        n = c.normalized();
        break;
      }
      case 4:
        through = w[pick(rng)] + (trial % 2 ? 1e-13 : 1e-9) * n;
        break;
      default:
        break;
    }
    const Plane below[1] = {{n, n.dot(through)}};
    const Plane above[1] = {{-n, -n.dot(through)}};
    const double v1 = clippedVolume(placed, below), v2 = clippedVolume(placed, above);
    CHECK(v1 >= 0.0);
    CHECK(v2 >= 0.0);
    CHECK(v1 + v2 == Approx(v).epsilon(1e-12));
  }
}
