#include "bench/microbench.hpp"

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <regex>
#include <stdexcept>

#include "backends/backend_factory.hpp"
#include "backends/nscd/broad_phase.hpp"
#include "backends/nscd/contact_solver.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "collision/polyhedron_contact.hpp"
#include "compaction/deposition.hpp"
#include "core/build_info.hpp"
#include "core/packing_io.hpp"
#include "core/population.hpp"
#include "core/random.hpp"

namespace confpack::bench {

namespace {

using core::Grain;
using core::Quat;
using core::ShapeKind;
using core::Vec3;

// ---------------------------------------------------------------------------------------------
// Fixtures. Each is built on first use and kept for the rest of the process: Google Benchmark
// calls a benchmark function several times (to size the iteration count, then once per
// repetition), and a deposit of 30,000 grains takes about a second.

/// Grain counts of the broad-phase and Gauss-Seidel series (the paper's piles: 1,900 to 30,400
/// spheres).
constexpr int kBroadPhaseSizes[] = {2000, 8000, 30000};
constexpr int kSweepSizes[] = {2000, 8000, 30000};
/// Grain counts of the whole-solve series (the factorisations of "cholesky" at 30,000 grains
/// would take minutes a repetition).
constexpr int kSolveSizes[] = {2000, 8000};
/// Pairs per narrow-phase fixture: enough different poses that the branch predictor cannot learn
/// them, few enough to stay in L2 (a sphere-sphere pass is ~10 us).
constexpr int kPairsPerType = 512;
/// Gaps of the narrow-phase poses, as a fraction of the smaller grain size: from a slight overlap
/// (what an unconverged step leaves) to just inside the alert distance (NscdSettings default
/// 0.03), so that every pair yields a contact, as the pairs that matter in a dense pile do.
constexpr double kGapMin = -0.005, kGapMax = 0.025;
/// Time step of the settling run and of the timed sweeps [t0], of the order of the fixed step.
constexpr double kDt = 1e-3;
/// Steps of nscd that settle the touching placeholder pile before the sweep is timed, and the
/// sweep cap during them: enough for the impulses to spread through the network, cheap enough
/// (the whole fixture, deposit included, takes about 0.9 s for 8,000 grains and 4.8 s for
/// 30,000).
constexpr int kSettleSteps = 10;
constexpr int kSettleSweeps = 50;
/// Steps the nscd backend takes a `--micro-pile` packing from rest before its step is timed: enough
/// to load the network and fill the contact cache, few enough to leave the pile where it was.
constexpr int kPileSteps = 5;
/// Their step [t0]: the adaptive step of a creep (0.04 to 0.07 on r0008 and msp-w10 at t = 30),
/// whose solves take hundreds of iterations where a step of 1e-3 takes tens.
constexpr double kPileDt = 0.05;
/// Expected solid fraction used to size the deposit boxes (the deposition default) [-].
constexpr double kSolidFraction = 0.6;
constexpr double kPileHeight = 16.0;  // [d_L]

/// Biperiodic box of height 16 that holds n unit spheres at the expected solid fraction.
core::BoxDef boxFor(int n) {
  core::PopulationDef pop;
  const double side = std::sqrt(n * pop.meanGrainVolume(pop.largeSize) / (kSolidFraction * kPileHeight));
  core::BoxDef box;
  box.lengthX = side;
  box.width = side;
  box.periodicY = true;
  box.height = kPileHeight;
  return box;
}

/// The deposit `confpack deposit` makes for this box (monodisperse spheres), with exactly n grains.
compaction::Deposit sphereDeposit(const core::BoxDef& box, int n, std::uint64_t seed) {
  core::PopulationDef pop;
  core::DepositionDef def;
  def.grainCount = static_cast<std::size_t>(n);
  return compaction::deposit(box, pop, def, seed);
}

struct BroadPhaseFixture {
  std::vector<Vec3> positions;
  std::vector<double> reach;
  std::unique_ptr<nscd::BroadPhase> broad;
  std::vector<nscd::CandidatePair> pairs;
};

BroadPhaseFixture makeBroadPhaseFixture(int n, std::uint64_t seed) {
  const core::BoxDef box = boxFor(n);
  const compaction::Deposit dep = sphereDeposit(box, n, seed);
  const nscd::NarrowPhase narrow(box, dep.grains, nscd::NscdSettings{}.alertDistance);
  BroadPhaseFixture f;
  for (std::size_t i = 0; i < dep.grains.size(); ++i) {
    f.positions.push_back(dep.grains[i].position);
    f.reach.push_back(narrow.reach(static_cast<int>(i)));
  }
  f.broad = std::make_unique<nscd::BroadPhase>(box, narrow.maxReach());
  return f;
}

enum class PairKind { SphereSphere, SphereWall, PinacoidWall, PinacoidSphere, PinacoidPinacoid, PinacoidFaceFace };

struct PairKindInfo {
  PairKind kind;
  const char* name;
};
constexpr PairKindInfo kPairKinds[] = {
    {PairKind::SphereSphere, "sphere-sphere"},         {PairKind::SphereWall, "sphere-wall"},
    {PairKind::PinacoidWall, "pinacoid-wall"},         {PairKind::PinacoidSphere, "pinacoid-sphere"},
    {PairKind::PinacoidPinacoid, "pinacoid-pinacoid"}, {PairKind::PinacoidFaceFace, "pinacoid-pinacoid-face"}};

struct NarrowPhaseFixture {
  core::BoxDef box;
  std::vector<Vec3> positions;
  std::vector<Quat> orientations;
  std::unique_ptr<nscd::NarrowPhase> narrow;
  std::vector<nscd::CandidatePair> pairs;  ///< grain-grain kinds
  std::vector<int> wallGrains;             ///< wall kinds: grains that touch the floor
  std::vector<nscd::ContactGeometry> out;
};

/// Signed gap between grains a (at pa) and b (at pb) along their exact closest features [d_L].
double exactGap(const Grain& a, const Vec3& pa, const Grain& b, const Vec3& pb) {
  constexpr double kNoAlert = 1e9;  // always report, whatever the distance
  const bool sphereA = a.shape == ShapeKind::Sphere, sphereB = b.shape == ShapeKind::Sphere;
  if (sphereA && sphereB) return (pb - pa).norm() - 0.5 * (a.size + b.size);
  if (sphereA) return exactGap(b, pb, a, pa);
  const core::ConvexPolyhedron polyA = a.polyhedron();
  const collision::PlacedPolyhedron placedA{&polyA, pa, a.orientation.toRotationMatrix()};
  std::optional<collision::PolyhedronContact> pc;
  if (sphereB) {
    pc = collision::collidePolyhedronSphere(placedA, pb, 0.5 * b.size, kNoAlert);
  } else {
    const core::ConvexPolyhedron polyB = b.polyhedron();
    pc = collision::collidePolyhedra(placedA, collision::PlacedPolyhedron{&polyB, pb, b.orientation.toRotationMatrix()},
                                     kNoAlert);
  }
  if (!pc) throw std::runtime_error("narrow-phase fixture: no gap for a pose");
  return pc->gap;
}

/// Unit vector uniform on the sphere (normalised 3-D Gaussian).
Vec3 randomDirection(core::Rng& rng) {
  Vec3 v;
  do v = Vec3(rng.normal(), rng.normal(), rng.normal());
  while (v.squaredNorm() < 1e-12);
  return v.normalized();
}

/// Grains of one shape with the population's size spread and, for pinacoids, uniform orientations.
std::vector<Grain> drawShapes(ShapeKind shape, int n, std::uint64_t seed) {
  core::PopulationDef pop;
  pop.shape = shape;
  return core::drawGrainCount(pop, static_cast<std::size_t>(n), seed);
}

// Touching poses. Grain-grain: b is placed from a along a random direction at the distance where
// their exact gap equals a drawn target (bisection: for convex shapes the signed gap along a ray
// from a's centre crosses any level once). Grain-wall: the grain sits above the floor of a
// biperiodic box (so collideWalls tests exactly one wall, and every call is one touching pair).
NarrowPhaseFixture makeNarrowPhaseFixture(PairKind kind, std::uint64_t seed) {
  core::Rng rng(seed, core::StreamId::Test, 1);  // synthetic poses, not part of any packing
  NarrowPhaseFixture f;
  f.box.lengthX = 1000.0;  // far larger than the poses: no periodic image is involved
  f.box.width = 1000.0;
  f.box.periodicY = true;
  std::vector<Grain> grains;
  const bool wall = kind == PairKind::SphereWall || kind == PairKind::PinacoidWall;
  if (wall) {
    grains = drawShapes(kind == PairKind::SphereWall ? ShapeKind::Sphere : ShapeKind::Pinacoid, kPairsPerType, seed);
    for (int i = 0; i < kPairsPerType; ++i) {
      Grain& g = grains[i];
      // Height of the centre above the lowest point of the grain.
      double below = 0.5 * g.size;
      if (g.shape == ShapeKind::Pinacoid) {
        g.position = Vec3::Zero();
        below = 0.0;
        for (const Vec3& v : g.worldVertices()) below = std::max(below, -v.z());
      }
      const double gap = rng.uniform(kGapMin, kGapMax) * g.size;
      g.position = Vec3(rng.uniform(0.0, f.box.lengthX), rng.uniform(0.0, f.box.width), below + gap);
      f.wallGrains.push_back(i);
    }
  } else {
    const ShapeKind shapeA = kind == PairKind::SphereSphere ? ShapeKind::Sphere : ShapeKind::Pinacoid;
    const ShapeKind shapeB = kind == PairKind::PinacoidPinacoid || kind == PairKind::PinacoidFaceFace
                                 ? ShapeKind::Pinacoid
                                 : ShapeKind::Sphere;
    const std::vector<Grain> as = drawShapes(shapeA, kPairsPerType, seed);
    const std::vector<Grain> bs = drawShapes(shapeB, kPairsPerType, seed + 1);
    int redraws = 0;
    for (int k = 0; k < kPairsPerType; ++k) {
      Grain a = as[k], b = bs[k];
      a.position = Vec3(rng.uniform(0.0, f.box.lengthX), rng.uniform(0.0, f.box.width), rng.uniform(1.0, 20.0));
      const double target = rng.uniform(kGapMin, kGapMax) * std::min(a.size, b.size);
      // b moves along base + s dir; s in [lo, hi] brackets the target gap.
      Vec3 base = a.position, dir;
      double lo = 0.0, hi = a.boundingRadius() + b.boundingRadius() + std::abs(target) + 0.1;
      if (kind == PairKind::PinacoidFaceFace) {
        // A face of b held against a face of a (the triple contacts of a dense pinacoid pile, which
        // take the clipping path): b turned so that its face normal is minus a's, spun at random
        // about it, face centroids offset by up to a tenth of the size in the contact plane.
        const core::ConvexPolyhedron polyA = a.polyhedron(), polyB = b.polyhedron();
        const int fa = static_cast<int>(rng.below(polyA.faces().size()));
        const int fb = static_cast<int>(rng.below(polyB.faces().size()));
        auto centroid = [](const core::ConvexPolyhedron& p, int face) {
          Vec3 c = Vec3::Zero();
          for (int v : p.faces()[face]) c += p.vertices()[v];
          return Vec3(c / static_cast<double>(p.faces()[face].size()));
        };
        dir = a.orientation * polyA.faceNormals()[fa];
        const Quat align = Quat::FromTwoVectors(polyB.faceNormals()[fb], -dir);
        b.orientation = Quat(Eigen::AngleAxisd(rng.uniform(0.0, 2.0 * std::numbers::pi), dir)) * align;
        const Vec3 lateral = randomDirection(rng).cross(dir).normalized() * rng.uniform(0.0, 0.1) * a.size;
        base = a.position + a.orientation * centroid(polyA, fa) - b.orientation * centroid(polyB, fb) + lateral;
        lo = -0.3 * std::min(a.size, b.size);
        hi = 0.3 * std::min(a.size, b.size);
      } else {
        b.orientation = rng.uniformQuaternion();
        dir = randomDirection(rng);
      }
      if (!(exactGap(a, a.position, b, base + lo * dir) < target &&
            exactGap(a, a.position, b, base + hi * dir) > target)) {
        // The gap does not cross the target in [lo, hi] (a face pose where other features meet
        // first): redraw, within a budget, so that a broken pose generator fails instead of looping.
        if (++redraws > 10 * kPairsPerType) throw std::runtime_error("narrow-phase fixture: no bracketing pose found");
        --k;
        continue;
      }
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        (exactGap(a, a.position, b, base + mid * dir) < target ? lo : hi) = mid;
      }
      b.position = base + hi * dir;
      // Mixed pairs come in both index orders, as they do out of the broad phase (a < b).
      if (kind == PairKind::PinacoidSphere && k % 2 == 1) std::swap(a, b);
      const int ia = static_cast<int>(grains.size());
      grains.push_back(a);
      grains.push_back(b);
      f.pairs.push_back(nscd::CandidatePair{ia, ia + 1, 0, 0});
    }
  }
  for (const Grain& g : grains) {
    f.positions.push_back(g.position);
    f.orientations.push_back(g.orientation);
  }
  f.narrow = std::make_unique<nscd::NarrowPhase>(f.box, grains, nscd::NscdSettings{}.alertDistance);
  f.out.reserve(grains.size());
  // The poses must be what they claim: every pair in contact (a fixture bug would otherwise time
  // the cheap rejection path).
  for (const nscd::CandidatePair& p : f.pairs) f.narrow->collidePair(p, f.positions, f.orientations, f.out);
  for (int i : f.wallGrains) f.narrow->collideWalls(i, f.positions, f.orientations, f.out);
  if (static_cast<int>(f.out.size()) != kPairsPerType)
    throw std::runtime_error(
        fmt::format("narrow-phase fixture: {} of {} poses in contact", f.out.size(), kPairsPerType));
  return f;
}

/// One step's contact problem on a settled pile: what ContactSolver::prepare needs, kept so that a
/// benchmark can prepare the rows afresh.
struct SolverFixture {
  core::BoxDef box;
  std::vector<nscd::ContactGeometry> contacts;
  std::vector<Vec3> positionMid;                   ///< q_m [d_L]
  std::vector<nscd::BodyInverseMass> bodies;       ///< one per grain, then the static walls
  std::vector<nscd::BodyVelocity> freeVelocities;  ///< v_free of the step
  std::vector<nscd::BodyVelocity> velocities;      ///< what the solver works on
  std::vector<double> reach;                       ///< broad-phase reach per grain [d_L]
  std::unique_ptr<nscd::BroadPhase> broad;
  std::vector<nscd::CandidatePair> pairs;
  nscd::ContactSolver solver;
  double rowsPerGrain = 0.0;
  double dt = kDt;  ///< the step [t0]

  /// Rows prepared from the contacts with zero impulses, velocities back to v_free (a cold start).
  void reset(const nscd::NscdSettings& settings) {
    velocities = freeVelocities;
    solver.prepare(contacts, positionMid, bodies, box, core::WallMaterial{}, dt, settings);  // frictionless walls
  }
};

/// One Gauss-Seidel sweep, whatever the default solver is.
nscd::NscdSettings oneSweepSettings() {
  nscd::NscdSettings s = nscd::defaultsFor(nscd::SolverKind::Nlgs);
  s.maxIterations = 1;
  s.minIterations = 1;
  return s;
}

/// MPRGP iterations per timed solve. The per-solve setup (Jacobi scaling, body rows, the operator
/// bound) is part of the time; near jamming a run's solves are longer (a few hundred iterations,
/// nscd_settings.hpp), which spreads it thinner: measured 53 and 35 M rows x iterations/s at 2,000
/// and 8,000 grains with 50 iterations, 57 and 37 M with 200. 50 keeps a repetition short.
constexpr int kMprgpIterations = 50;

nscd::NscdSettings mprgpSettings() {
  nscd::NscdSettings s = nscd::defaultsFor(nscd::SolverKind::Mprgp);
  s.maxIterations = kMprgpIterations;
  s.tolerance = std::numeric_limits<double>::min();  // never converged: always kMprgpIterations
  return s;
}

// A realistic contact network fast: spheres the size of the placeholders, at the placeholder
// centres, touch their three supports (that is how the deposition seats them), so the pile starts
// as a connected network (Z about 6) with no fall to wait for. The nscd backend (Gauss-Seidel,
// capped sweeps: the cheapest settling) then runs a few steps of gravity on it, and one step's
// phases are rebuilt from its state: q_m, inverse masses, free velocities, pairs and contacts.
SolverFixture fixtureAfter(const core::SystemDef& system, const core::ContactBackend& backend, double dt);

SolverFixture makeSolverFixture(int n, std::uint64_t seed) {
  const core::BoxDef box = boxFor(n);
  const compaction::Deposit dep = sphereDeposit(box, n, seed);
  core::SystemDef system;
  system.box = box;
  system.grains = dep.grains;
  for (std::size_t i = 0; i < dep.grains.size(); ++i) {
    system.grains[i].size = dep.placeholderDiameter;
    system.grains[i].position = dep.placeholders[i];
  }
  const nlohmann::json options = {{"solver", "nlgs"}, {"max_iterations", kSettleSweeps}, {"min_iterations", 1}};
  const std::unique_ptr<core::ContactBackend> backend = backends::makeBackend("nscd", system, options);
  for (int s = 0; s < kSettleSteps; ++s) backend->step(kDt);
  return fixtureAfter(system, *backend, kDt);
}

// A pile of the user's (`--micro-pile`, a packing file, e.g. of a run stopped in its creep): the
// nscd backend at its defaults takes it from rest for kPileSteps steps, which loads its contact
// network and warms the impulses, and the next step's phases are rebuilt as above.
SolverFixture makePileFixture(const std::filesystem::path& file) {
  const core::Packing packing = core::readPacking(file);
  core::SystemDef system;
  system.box = packing.box;
  system.grains = packing.grains;
  system.walls = packing.walls;
  const std::unique_ptr<core::ContactBackend> backend = backends::makeBackend("nscd", system, nlohmann::json::object());
  for (int s = 0; s < kPileSteps; ++s) backend->step(kPileDt);
  return fixtureAfter(system, *backend, kPileDt);
}

// One step's contact problem after the backend's last step: q_m, inverse masses, free velocities,
// pairs and contacts, and the rows of a cold start.
SolverFixture fixtureAfter(const core::SystemDef& system, const core::ContactBackend& backend, double dt) {
  const core::BoxDef& box = system.box;
  const std::size_t n = system.grains.size();
  SolverFixture f;
  f.box = box;
  f.dt = dt;
  const nscd::NscdSettings settings;
  const std::vector<core::BodyState>& states = backend.states();
  std::vector<Quat> orientations;
  f.bodies.resize(states.size() + 1);  // last: the static walls
  f.freeVelocities.resize(states.size() + 1);
  for (std::size_t i = 0; i < states.size(); ++i) {
    const Grain& g = system.grains[i];
    // q_m = q + dt (1 - theta) v; v_free = v + dt g (spheres: no gyroscopic term).
    f.positionMid.push_back(states[i].position + dt * (1.0 - settings.theta) * states[i].velocity);
    orientations.push_back(states[i].orientation);
    const core::Mat3 rot = states[i].orientation.toRotationMatrix();
    f.bodies[i].invMass = 1.0 / (system.density * g.volume());
    f.bodies[i].invInertia = rot * g.bodyInertia(system.density).inverse() * rot.transpose();
    f.freeVelocities[i].v = states[i].velocity + dt * system.gravity;
    f.freeVelocities[i].w = states[i].angularVelocity;
  }
  nscd::NarrowPhase narrow(box, system.grains, settings.alertDistance);
  for (std::size_t i = 0; i < states.size(); ++i) f.reach.push_back(narrow.reach(static_cast<int>(i)));
  f.broad = std::make_unique<nscd::BroadPhase>(box, narrow.maxReach());
  f.broad->findPairs(f.positionMid, f.reach, f.pairs);
  for (const nscd::CandidatePair& p : f.pairs) narrow.collidePair(p, f.positionMid, orientations, f.contacts);
  for (int i = 0; i < static_cast<int>(states.size()); ++i)
    narrow.collideWalls(i, f.positionMid, orientations, f.contacts);
  f.reset(settings);
  f.rowsPerGrain = static_cast<double>(f.solver.rowCount()) / static_cast<double>(n);
  if (f.solver.rowCount() == 0) throw std::runtime_error("solver fixture: the settled pile has no contact rows");
  return f;
}

/// The fixture of `key`, built by `make` on first use. On failure the benchmark is skipped with
/// the message (runMicroBench then fails the whole run) and nullptr is returned.
template <class Fixture, class Key>
Fixture* cachedFixture(benchmark::State& state, const Key& key, const std::function<Fixture()>& make) {
  static std::map<Key, std::unique_ptr<Fixture>> cache;
  auto it = cache.find(key);
  if (it == cache.end()) {
    try {
      it = cache.emplace(key, std::make_unique<Fixture>(make())).first;
    } catch (const std::exception& e) {
      state.SkipWithError(e.what());
      return nullptr;
    }
  }
  return it->second.get();
}

// ---------------------------------------------------------------------------------------------
// Benchmarks.

// The timed loop of both broad-phase benchmarks: grains through findPairs, and pairs per grain.
void timeFindPairs(benchmark::State& state, nscd::BroadPhase& broad, const std::vector<Vec3>& positions,
                   const std::vector<double>& reach, std::vector<nscd::CandidatePair>& pairs) {
  for (auto _ : state) {
    broad.findPairs(positions, reach, pairs);
    benchmark::DoNotOptimize(pairs.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(positions.size()));
  state.counters["pairs_per_grain"] = static_cast<double>(pairs.size()) / static_cast<double>(positions.size());
}

void broadPhaseBenchmark(benchmark::State& state, int n, std::uint64_t seed) {
  BroadPhaseFixture* f =
      cachedFixture<BroadPhaseFixture, int>(state, n, [&] { return makeBroadPhaseFixture(n, seed); });
  if (f) timeFindPairs(state, *f->broad, f->positions, f->reach, f->pairs);
}

// The same search on the settled pile of the solver benchmarks, where every grain touches its
// neighbours: the pairs that a compaction step finds (about 3 per grain) instead of a loose deposit's.
void pileBroadPhaseBenchmark(benchmark::State& state, int n, std::uint64_t seed) {
  SolverFixture* f = cachedFixture<SolverFixture, int>(state, n, [&] { return makeSolverFixture(n, seed); });
  if (f) timeFindPairs(state, *f->broad, f->positionMid, f->reach, f->pairs);
}

void narrowPhaseBenchmark(benchmark::State& state, PairKind kind, std::uint64_t seed) {
  NarrowPhaseFixture* f =
      cachedFixture<NarrowPhaseFixture, PairKind>(state, kind, [&] { return makeNarrowPhaseFixture(kind, seed); });
  if (!f) return;
  double points = 0.0;
  for (auto _ : state) {
    f->out.clear();
    for (const nscd::CandidatePair& p : f->pairs) f->narrow->collidePair(p, f->positions, f->orientations, f->out);
    for (int i : f->wallGrains) f->narrow->collideWalls(i, f->positions, f->orientations, f->out);
    benchmark::DoNotOptimize(f->out.data());
    benchmark::ClobberMemory();
  }
  for (const nscd::ContactGeometry& c : f->out) points += c.pointCount;
  state.SetItemsProcessed(state.iterations() * kPairsPerType);
  state.counters["points_per_pair"] = points / kPairsPerType;
}

void sweepBenchmark(benchmark::State& state, int n, std::uint64_t seed) {
  SolverFixture* f = cachedFixture<SolverFixture, int>(state, n, [&] { return makeSolverFixture(n, seed); });
  if (!f) return;
  const nscd::NscdSettings settings = oneSweepSettings();
  f->reset(settings);
  // The timed call must be one Gauss-Seidel sweep, not some other solver's iteration.
  if (f->solver.solve(f->velocities, settings) != 1) {
    state.SkipWithError("the contact solver did not stop after one sweep");
    return;
  }
  // Every iteration sweeps the same rows again, so the pile drifts towards rest and the impulses
  // converge; that does not change the cost of a sweep (measured at 2,000 grains: 112 M rows/s over
  // 1,200 iterations and over 25,000).
  for (auto _ : state) {
    benchmark::DoNotOptimize(f->solver.solve(f->velocities, settings));
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * f->solver.rowCount());
  state.counters["rows_per_grain"] = f->rowsPerGrain;
}

// Each timed iteration is one cold MPRGP solve of kMprgpIterations iterations (rows prepared
// afresh outside the timing, so every solve does the same work). Items are rows times iterations,
// comparable with Gauss-Seidel's rows per sweep although an MPRGP iteration costs about two sweeps.
void mprgpBenchmark(benchmark::State& state, int n, std::uint64_t seed) {
  SolverFixture* f = cachedFixture<SolverFixture, int>(state, n, [&] { return makeSolverFixture(n, seed); });
  if (!f) return;
  const nscd::NscdSettings settings = mprgpSettings();
  std::int64_t iterations = 0;
  for (auto _ : state) {
    state.PauseTiming();
    f->reset(settings);
    state.ResumeTiming();
    iterations += f->solver.solve(f->velocities, settings);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(iterations * f->solver.rowCount());
  state.counters["iterations_per_solve"] =
      state.iterations() > 0 ? static_cast<double>(iterations) / static_cast<double>(state.iterations()) : 0.0;
  state.counters["rows_per_grain"] = f->rowsPerGrain;
}

// Each timed iteration is one cold MPRGP solve to the default tolerance (1e-10) with the given
// preconditioner, rows prepared afresh outside the timing: what the "cholesky" preconditioner's
// fewer iterations cost against the sweeps' many (docs/performance.md, "The preconditioner and the creep's solve").
// Items are solves; the counters say how many iterations and factorisations a solve took.
void timeMprgpSolves(benchmark::State& state, SolverFixture& f, const std::string& preconditioner) {
  nscd::NscdSettings settings = nscd::defaultsFor(nscd::SolverKind::Mprgp);
  settings.preconditioner = preconditioner == "cholesky" ? nscd::PreconditionerKind::Cholesky
                                                         : nscd::PreconditionerKind::SymmetricGaussSeidel;
  std::int64_t iterations = 0, factorisations = 0;
  for (auto _ : state) {
    state.PauseTiming();
    f.reset(settings);
    state.ResumeTiming();
    iterations += f.solver.solve(f.velocities, settings);
    factorisations += f.solver.mprgpSteps().factorisations + f.solver.mprgpSteps().factorUpdates;
    benchmark::ClobberMemory();
  }
  const double solves = std::max<double>(1.0, static_cast<double>(state.iterations()));
  state.SetItemsProcessed(state.iterations());
  state.counters["iterations_per_solve"] = static_cast<double>(iterations) / solves;
  state.counters["rows"] = f.solver.rowCount();
  // Only where it can be non-zero: a counter that is 0 in every repetition has an undefined
  // coefficient of variation, which Google Benchmark writes as a NaN its JSON reader refuses.
  if (settings.preconditioner == nscd::PreconditionerKind::Cholesky)
    state.counters["factor_changes_per_solve"] = static_cast<double>(factorisations) / solves;
}

void mprgpSolveBenchmark(benchmark::State& state, const std::string& preconditioner, int n, std::uint64_t seed) {
  SolverFixture* f = cachedFixture<SolverFixture, int>(state, n, [&] { return makeSolverFixture(n, seed); });
  if (f) timeMprgpSolves(state, *f, preconditioner);
}

void pileSolveBenchmark(benchmark::State& state, const std::string& preconditioner, const std::filesystem::path& file) {
  SolverFixture* f =
      cachedFixture<SolverFixture, std::string>(state, file.string(), [&] { return makePileFixture(file); });
  if (f) timeMprgpSolves(state, *f, preconditioner);
}

struct Entry {
  std::string name;
  std::function<void(benchmark::State&, std::uint64_t)> run;
};

const std::vector<Entry>& entries() {
  static const std::vector<Entry> list = [] {
    std::vector<Entry> e;
    for (int n : kBroadPhaseSizes)
      e.push_back({fmt::format("BroadPhase/spheres/{}", n),
                   [n](benchmark::State& s, std::uint64_t seed) { broadPhaseBenchmark(s, n, seed); }});
    for (int n : kSweepSizes)
      e.push_back({fmt::format("BroadPhase/pile/{}", n),
                   [n](benchmark::State& s, std::uint64_t seed) { pileBroadPhaseBenchmark(s, n, seed); }});
    for (const PairKindInfo& k : kPairKinds)
      e.push_back({fmt::format("NarrowPhase/{}", k.name),
                   [kind = k.kind](benchmark::State& s, std::uint64_t seed) { narrowPhaseBenchmark(s, kind, seed); }});
    for (int n : kSweepSizes)
      e.push_back({fmt::format("GaussSeidelSweep/spheres/{}", n),
                   [n](benchmark::State& s, std::uint64_t seed) { sweepBenchmark(s, n, seed); }});
    for (int n : kSweepSizes)
      e.push_back({fmt::format("MprgpIteration/spheres/{}", n),
                   [n](benchmark::State& s, std::uint64_t seed) { mprgpBenchmark(s, n, seed); }});
    for (const char* preconditioner : {"sgs", "cholesky"})
      for (int n : kSolveSizes)
        e.push_back({fmt::format("MprgpSolve/{}/spheres/{}", preconditioner, n),
                     [n, p = std::string(preconditioner)](benchmark::State& s, std::uint64_t seed) {
                       mprgpSolveBenchmark(s, p, n, seed);
                     }});
    return e;
  }();
  return list;
}

/// Google Benchmark's reading of a filter: "all" is everything, a leading '-' negates.
bool filterSelects(const std::string& filter, const std::string& name) {
  std::string spec = filter == "all" ? "." : filter;
  const bool negative = !spec.empty() && spec[0] == '-';
  if (negative) spec.erase(0, 1);
  const bool match = std::regex_search(name, std::regex(spec, std::regex::extended));
  return match != negative;
}

}  // namespace

// Every benchmark, with the two of `--micro-pile` when it names a packing.
std::vector<Entry> entriesFor(const MicroBenchDef& def) {
  std::vector<Entry> e = entries();
  if (!def.pile.empty())
    for (const char* preconditioner : {"sgs", "cholesky"})
      e.push_back({fmt::format("MprgpSolve/{}/pile", preconditioner),
                   [file = def.pile, p = std::string(preconditioner)](benchmark::State& s, std::uint64_t) {
                     pileSolveBenchmark(s, p, file);
                   }});
  return e;
}

namespace {

void requirePackingFile(const std::filesystem::path& pile) {
  if (!std::filesystem::is_regular_file(pile))
    throw std::invalid_argument(fmt::format("--micro-pile: {}: not a readable packing file", pile.string()));
}

}  // namespace

void validatePileDump(const std::filesystem::path& pile, const std::filesystem::path& dir) {
  if (std::filesystem::exists(dir))
    throw std::invalid_argument(fmt::format("--micro-dump {}: already exists", dir.string()));
  requirePackingFile(pile);
}

void dumpPileBlock(const std::filesystem::path& pile, const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  validatePileDump(pile, dir);
  SolverFixture f = makePileFixture(pile);
  const nscd::NscdSettings settings;  // MPRGP to 1e-10, SGS: the default
  f.reset(settings);
  const int iterations = f.solver.solve(f.velocities, settings);
  const nscd::ContactRows& rows = f.solver.rows();
  if (!rows.frictionRows().empty())
    throw std::invalid_argument(
        "--micro-dump: the pile has side-wall friction rows; only frictionless blocks are dumped");

  std::string rowText = "a,b,nx,ny,nz,axn_x,axn_y,axn_z,bxn_x,bxn_y,bxn_z,bias,r\n";
  for (const nscd::NormalRow& r : rows.normalRows())
    rowText +=
        fmt::format("{},{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n",
                    r.a, r.b, r.n.x(), r.n.y(), r.n.z(), r.axn.x(), r.axn.y(), r.axn.z(), r.bxn.x(), r.bxn.y(),
                    r.bxn.z(), r.bias, f.solver.normalImpulse(r.c, r.p));
  std::string bodyText = "inv_mass,i00,i01,i02,i10,i11,i12,i20,i21,i22,vx,vy,vz,wx,wy,wz,x,y,z\n";
  for (std::size_t i = 0; i < f.bodies.size(); ++i) {
    const nscd::BodyInverseMass& b = f.bodies[i];
    const nscd::BodyVelocity& v = f.freeVelocities[i];
    bodyText += fmt::format("{:.17g}", b.invMass);
    for (int k = 0; k < 9; ++k) bodyText += fmt::format(",{:.17g}", b.invInertia(k / 3, k % 3));
    bodyText += fmt::format(",{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}", v.v.x(), v.v.y(), v.v.z(), v.w.x(),
                            v.w.y(), v.w.z());
    const Vec3 x = i < f.positionMid.size() ? f.positionMid[i] : Vec3::Zero();  // the walls: none
    bodyText += fmt::format(",{:.17g},{:.17g},{:.17g}\n", x.x(), x.y(), x.z());
  }
  const nlohmann::json block = {{"packing", pile.string()},         {"dt", f.dt},
                                {"rows", rows.normalRows().size()}, {"bodies", f.bodies.size()},
                                {"mprgp_iterations", iterations},   {"mprgp_residual", f.solver.residual()},
                                {"tolerance", settings.tolerance}};
  // Written whole or not at all: a temporary folder beside `dir`, renamed once complete.
  const fs::path tmp = dir.string() + fmt::format(".tmp-{}", ::getpid());
  try {
    fs::create_directories(tmp);
    core::writeFileAtomically(tmp / "rows.csv", rowText);
    core::writeFileAtomically(tmp / "bodies.csv", bodyText);
    core::writeFileAtomically(tmp / "block.json", block.dump(2));
    fs::rename(tmp, dir);
  } catch (const fs::filesystem_error& e) {
    std::error_code ignored;
    fs::remove_all(tmp, ignored);
    throw std::runtime_error(fmt::format("--micro-dump {}: {}", dir.string(), e.code().message()));
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(tmp, ignored);
    throw;
  }
}

const std::vector<std::string>& microBenchNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Entry& e : entries()) out.push_back(e.name);
    return out;
  }();
  return names;
}

void validateMicroBench(const MicroBenchDef& def) {
  if (!def.pile.empty()) requirePackingFile(def.pile);
  if (def.repetitions < 1)
    throw std::invalid_argument(fmt::format("--micro-repetitions: must be at least 1 (got {})", def.repetitions));
  if (!(def.minTime > 0.0) || !std::isfinite(def.minTime))
    throw std::invalid_argument(fmt::format("--micro-min-time: must be a positive number (got {})", def.minTime));
  try {
    std::vector<std::string> names;
    for (const Entry& e : entriesFor(def)) names.push_back(e.name);
    if (std::none_of(names.begin(), names.end(), [&](const std::string& n) { return filterSelects(def.filter, n); }))
      throw std::invalid_argument(
          fmt::format("--micro-filter '{}' selects no benchmark (names: {})", def.filter, fmt::join(names, ", ")));
  } catch (const std::regex_error& e) {
    throw std::invalid_argument(fmt::format("--micro-filter '{}' is not a valid regex ({})", def.filter, e.what()));
  }
}

namespace {

/// The creep block's target speed-up over SGS-preconditioned MPRGP: what a multilevel solve must
/// give, a step in tens of iterations where SGS takes hundreds to a thousand.
constexpr double kCreepBlockSpeedup = 5.0;

/// One pile solve of Google Benchmark's report: its median (or only) wall time a solve [s] and
/// its iterations and rows, by preconditioner.
struct PileSolve {
  double seconds = 0.0;
  double iterations = 0.0;
  double rows = 0.0;
};

std::map<std::string, PileSolve> pileSolves(const nlohmann::json& report) {
  static const std::regex name("^MprgpSolve/([a-z]+)/pile$");
  std::map<std::string, PileSolve> out;
  for (const nlohmann::json& b : report.value("benchmarks", nlohmann::json::array())) {
    std::smatch m;
    const std::string runName = b.value("run_name", b.value("name", std::string()));
    if (!std::regex_match(runName, m, name)) continue;
    // With repetitions only the aggregates are written: take the median; with one, the run.
    const bool aggregate = b.value("run_type", std::string()) == "aggregate";
    if (aggregate && b.value("aggregate_name", std::string()) != "median") continue;
    static const std::map<std::string, double> seconds = {{"ns", 1e-9}, {"us", 1e-6}, {"ms", 1e-3}, {"s", 1.0}};
    const auto unit = seconds.find(b.value("time_unit", std::string("us")));
    if (unit == seconds.end()) continue;
    out[m[1].str()] = {b.value("real_time", 0.0) * unit->second, b.value("iterations_per_solve", 0.0),
                       b.value("rows", 0.0)};
  }
  return out;
}

}  // namespace

nlohmann::json microTargets(const nlohmann::json& report) {
  nlohmann::json out = nlohmann::json::array();
  const std::map<std::string, PileSolve> solves = pileSolves(report);
  const auto sgs = solves.find("sgs");
  if (sgs == solves.end()) return out;
  const std::string statement = fmt::format(
      "creep block (--micro-pile): a step solved to 1e-10 at least {:g} times faster than SGS-preconditioned MPRGP",
      kCreepBlockSpeedup);
  const PileSolve& base = sgs->second;
  std::optional<std::pair<std::string, PileSolve>> best;
  for (const auto& [p, s] : solves)
    if (p != "sgs" && (!best || s.seconds < best->second.seconds)) best = std::make_pair(p, s);
  if (!best) {
    out.push_back({{"target", statement},
                   {"figure", fmt::format("sgs alone ran: {:.1f} ms, {:.0f} iterations, {:.0f} rows",
                                          1e3 * base.seconds, base.iterations, base.rows)},
                   {"met", nullptr}});
    return out;
  }
  const double speedup = base.seconds / best->second.seconds;
  out.push_back(
      {{"target", statement},
       {"figure", fmt::format("{} {:.2g} times sgs's speed: {:.1f} ms against {:.1f} ms a solve, {:.0f} against {:.0f} "
                              "iterations, {:.0f} rows",
                              best->first, speedup, 1e3 * best->second.seconds, 1e3 * base.seconds,
                              best->second.iterations, base.iterations, base.rows)},
       {"met", speedup >= kCreepBlockSpeedup}});
  return out;
}

nlohmann::json runMicroBench(const MicroBenchDef& def, const std::filesystem::path& out) {
  validateMicroBench(def);
  for (const Entry& e : entriesFor(def))
    benchmark::RegisterBenchmark(e.name.c_str(), [run = e.run, seed = def.seed](benchmark::State& s) {
      run(s, seed);
    })->Unit(benchmark::kMicrosecond);
  benchmark::AddCustomContext("confpack_version", core::version());
  benchmark::AddCustomContext("confpack_revision", core::sourceRevision());
  benchmark::AddCustomContext("confpack_seed", std::to_string(def.seed));

  // Google Benchmark writes its report itself, into a temporary file next to `out`; once the run
  // has succeeded the report goes to `out` with its targets, atomically.
  const std::filesystem::path dir = out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
  const std::filesystem::path tmp = dir / fmt::format(".{}.tmp-{}", out.filename().string(), ::getpid());
  std::vector<std::string> args = {"confpack-bench-micro",
                                   "--benchmark_filter=" + def.filter,
                                   fmt::format("--benchmark_repetitions={}", def.repetitions),
                                   fmt::format("--benchmark_min_time={}", def.minTime),
                                   "--benchmark_out=" + tmp.string(),
                                   "--benchmark_out_format=json",
                                   "--benchmark_report_aggregates_only=true"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int argc = static_cast<int>(args.size());
  try {
    // Google Benchmark ends the process (exit 1, its own message) when it cannot open its output:
    // find out first, and fail like every other command.
    if (!std::ofstream(tmp)) throw std::runtime_error(fmt::format("{}: cannot create the report file", tmp.string()));
    benchmark::Initialize(&argc, argv.data());
    const std::size_t ran = benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    if (ran == 0) throw std::runtime_error(fmt::format("--micro-filter '{}' ran no benchmark", def.filter));
    nlohmann::json report;
    {
      std::ifstream in(tmp);
      report = nlohmann::json::parse(in, nullptr, false);
    }
    if (report.is_discarded() || !report.contains("benchmarks"))
      throw std::runtime_error(fmt::format("{}: Google Benchmark wrote no readable report", tmp.string()));
    for (const nlohmann::json& b : report["benchmarks"])
      if (b.value("error_occurred", false))
        throw std::runtime_error(
            fmt::format("{}: {}", b.value("name", std::string("?")), b.value("error_message", std::string("failed"))));
    report["targets"] = microTargets(report);
    core::writeFileAtomically(out, report.dump(2));
    std::filesystem::remove(tmp);
    return report["targets"];
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
}

}  // namespace confpack::bench
