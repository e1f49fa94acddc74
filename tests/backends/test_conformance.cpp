// The conformance suite: the same physics tests, with analytic oracles, run against every backend
// named by backends::backendNames() (one suite for both backends).
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "backends/backend_factory.hpp"
#include "core/backend.hpp"
#include "core/random.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using core::Vec3;

namespace {

// ---------------------------------------------------------------------------------------------
// Per-backend tolerances. Every value that differs from the default says why.
struct Tolerances {
  /// Free fall: |z - z_exact| <= freeFallPerTdt * g t dt (+ round-off). 0: exact integrator.
  double freeFallPerTdt = 0.0;
  /// Resting sphere / pinacoid: relative error of the floor force against m g [-].
  double restingForceRel = 1e-8;
  /// Resting sphere / pinacoid: largest displacement over the run [d_L].
  double restingDrift = 1e-9;
  /// Column of beads: relative error of the k-th contact force against k m g [-].
  double columnForceRel = 1e-6;
  /// Settled pile: relative error of the floor reaction against the total weight [-].
  double floorReactionRel = 1e-6;
  /// Sphere on a frictional wall: relative error of the acceleration [-].
  double wallAccelerationRel = 1e-6;
  /// Settled pile: kinetic energy below which the pile counts as at rest [m g d_L, total].
  double restKinetic = 1e-14;
  /// Periodic pair versus interior pair: absolute difference of forces [m g] and positions [d_L].
  /// Round-off of positions near x = 20 versus x = 10 changes the sweep at which the solver stops;
  /// two strongly coupled rows converge slowly, so converged answers agree to ~1e-9, not 1e-15.
  double periodicAbs = 1e-8;
  /// Options used by every test of this suite.
  nlohmann::json options = nlohmann::json::object();
  /// Options for the tests that need an exactly converged solver (column, pile).
  nlohmann::json tightOptions = nlohmann::json::object();
};

const Tolerances& tolerancesFor(std::string_view backend) {
  static const std::map<std::string, Tolerances, std::less<>> table = [] {
    std::map<std::string, Tolerances, std::less<>> t;
    Tolerances nscd;
    // Converge the Gauss-Seidel sweeps far below the asserted 1e-6 so that the column and pile
    // checks measure the physics, not the stopping rule.
    nscd.tightOptions = {{"tolerance", 1e-11}, {"max_iterations", 20000}};
    t["nscd"] = nscd;
    // The same backend with Gauss-Seidel ("nlgs") instead of its default MPRGP passes the same
    // suite (its defaults: tolerance 1e-6, 2000 sweeps).
    Tolerances nlgs = nscd;
    nlgs.options = {{"solver", "nlgs"}};
    nlgs.tightOptions = {{"solver", "nlgs"}, {"tolerance", 1e-11}, {"max_iterations", 20000}};
    t["nscd-nlgs"] = nlgs;
    Tolerances bullet;
    // Bullet integrates with semi-implicit Euler: v += g dt, then x += v dt, so after n steps
    // z = z0 - g dt^2 n (n + 1) / 2 = z0 - g t^2 / 2 - g t dt / 2: a first-order error of g t dt / 2.
    bullet.freeFallPerTdt = 0.5;
    // Like nscd: converge the sequential-impulse sweeps (early exit at a sweep correction of
    // 1e-10 |g| dt, cap 2000) so the column and pile checks measure the physics.
    bullet.tightOptions = {{"residual_threshold", 1e-10}, {"iterations", 2000}};
    t["bullet"] = bullet;
    return t;
  }();
  const auto it = table.find(backend);
  if (it == table.end()) FAIL("no tolerance entry for backend " << backend);
  return it->second;
}

// ---------------------------------------------------------------------------------------------

/// What the suite runs: every backend, plus "nscd-nlgs" (nscd with solver = nlgs; the part
/// after '-' names a variant whose options come from tolerancesFor()).
std::vector<std::string> variants() {
  std::vector<std::string> v(backends::backendNames().begin(), backends::backendNames().end());
  v.push_back("nscd-nlgs");
  return v;
}

/// The backend of a variant ("nscd-nlgs" is nscd with the options that select Gauss-Seidel).
std::unique_ptr<core::ContactBackend> makeVariant(std::string_view name, const core::SystemDef& system,
                                                  const nlohmann::json& options) {
  return backends::makeBackend(name.substr(0, name.find('-')), system, options);
}

using confpack::testing::sphere;

double sphereMass(double d) {
  return std::numbers::pi / 6.0 * d * d * d;
}

using confpack::testing::boxSystem;

/// Sum of the forces of the contacts of grain i with wall w (force on the wall).
Vec3 wallForce(const std::vector<core::Contact>& contacts, core::WallId w) {
  Vec3 f = Vec3::Zero();
  for (const auto& c : contacts)
    if (c.b == static_cast<int>(w)) f += c.forceOnB();
  return f;
}

/// A pinacoid (L = G = E = 1, alpha = 60 deg) lying on a trapezoid face on the floor.
core::Grain pinacoidOnFace(double x, double y) {
  // The trapezoid faces have outward normals (0, +-1, +-1)/sqrt(2) for G = E; a rotation of
  // 45 degrees about x brings (0, -1, -1)/sqrt(2) onto -z.
  const core::Quat onFace(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));
  return confpack::testing::withBottomAt(confpack::testing::pinacoid(1.0, Vec3(x, y, 0.0), onFace), 0.0);
}

}  // namespace

TEST_CASE("free fall follows z0 - g t^2 / 2 at several time steps", "[conformance]") {
  const std::string name(GENERATE(from_range(variants())));
  const double dt = GENERATE(1e-3, 4e-3, 1e-2);
  INFO("backend " << name << ", dt " << dt);
  const Tolerances& tol = tolerancesFor(name);
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  const double z0 = 50.0;
  s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, z0)));
  const auto backend = makeVariant(name, s, tol.options);
  const int steps = static_cast<int>(std::lround(1.0 / dt));
  for (int k = 0; k < steps; ++k) backend->step(dt);
  const double t = steps * dt;
  const core::BodyState& b = backend->states()[0];
  CHECK(std::abs(b.position.z() - (z0 - 0.5 * t * t)) <= tol.freeFallPerTdt * t * dt + 1e-12 * z0);
  CHECK(b.velocity.z() == Approx(-t).epsilon(1e-12));
  CHECK(std::abs(b.position.x() - 10.0) < 1e-12);
  CHECK(std::abs(b.position.y() - 5.0) < 1e-12);
  CHECK(backend->contacts().empty());
}

TEST_CASE("a sphere resting on the floor carries m g and does not drift", "[conformance]") {
  const std::string name(GENERATE(from_range(variants())));
  const double dt = GENERATE(1e-3, 5e-3);
  INFO("backend " << name << ", dt " << dt);
  const Tolerances& tol = tolerancesFor(name);
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  const double d = 1.2;
  s.grains.push_back(sphere(d, Vec3(10.0, 5.0, 0.5 * d)));
  const auto backend = makeVariant(name, s, tol.options);
  double drift = 0.0;
  for (int k = 0; k < 500; ++k) {
    backend->step(dt);
    drift = std::max(drift, (backend->states()[0].position - Vec3(10.0, 5.0, 0.5 * d)).norm());
  }
  CHECK(drift <= tol.restingDrift);
  const Vec3 f = wallForce(backend->contacts(), core::WallId::Floor);
  CHECK(f.z() == Approx(-sphereMass(d)).epsilon(tol.restingForceRel));  // the floor is pushed down by m g
  CHECK(std::abs(f.x()) + std::abs(f.y()) < 1e-12);
}

TEST_CASE("a pinacoid lying on a face: one contact with >= 3 points, force m g, no torque", "[conformance]") {
  const std::string name(GENERATE(from_range(variants())));
  INFO("backend " << name);
  const Tolerances& tol = tolerancesFor(name);
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  s.grains.push_back(pinacoidOnFace(10.0, 5.0));
  const Vec3 start = s.grains[0].position;
  const double m = s.grains[0].volume();
  const auto backend = makeVariant(name, s, tol.options);
  const double dt = 1e-3;
  double drift = 0.0;
  for (int k = 0; k < 500; ++k) {
    backend->step(dt);
    drift = std::max(drift, (backend->states()[0].position - start).norm());
  }
  CHECK(drift <= tol.restingDrift);
  REQUIRE(backend->contacts().size() == 1);
  const core::Contact& c = backend->contacts()[0];
  CHECK(c.b == static_cast<int>(core::WallId::Floor));
  CHECK(c.points.size() >= 3);
  CHECK(c.type == core::ContactType::Triple);
  CHECK(c.normalForce() == Approx(m).epsilon(tol.restingForceRel));
  // Moment of the contact forces about the centroid: zero at rest (gravity has none).
  const Vec3 centre = backend->states()[0].position;
  Vec3 moment = Vec3::Zero();
  for (const auto& p : c.points) moment += (p.position - centre).cross(-(p.normalForce * c.normal + p.tangentForce));
  CHECK(moment.norm() < tol.restingForceRel * m * 1.0 + 1e-12);
}

TEST_CASE("a frictionless column of 10 beads: the k-th contact from the top carries k m g", "[conformance]") {
  const std::string name(GENERATE(from_range(variants())));
  const double dt = GENERATE(1e-3, 4e-3);
  INFO("backend " << name << ", dt " << dt);
  const Tolerances& tol = tolerancesFor(name);
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  const int n = 10;
  for (int k = 0; k < n; ++k) s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 0.5 + k)));
  const auto backend = makeVariant(name, s, tol.tightOptions);
  for (int k = 0; k < 200; ++k) backend->step(dt);
  const double mg = sphereMass(1.0);
  int seen = 0;
  for (const core::Contact& c : backend->contacts()) {
    if (c.normalForce() <= 0.0) continue;
    ++seen;
    if (c.b == static_cast<int>(core::WallId::Floor)) {
      CHECK(c.a == 0);
      CHECK(c.normalForce() == Approx(n * mg).epsilon(tol.columnForceRel));
      continue;
    }
    REQUIRE(c.b >= 0);
    const int lower = std::min(c.a, c.b);
    CHECK(std::abs(c.a - c.b) == 1);
    // Contact between beads j and j+1 (from the bottom) supports the n - 1 - j beads above it.
    INFO("contact " << c.a << "-" << c.b);
    CHECK(c.normalForce() == Approx((n - 1 - lower) * mg).epsilon(tol.columnForceRel));
  }
  CHECK(seen == n);
  // The column does not move.
  for (int k = 0; k < n; ++k) CHECK((backend->states()[k].position - Vec3(10.0, 5.0, 0.5 + k)).norm() < 1e-6);
}

TEST_CASE("a settled frictionless pile: the floor carries the weight, the side walls push horizontally",
          "[conformance]") {
  const std::string name(GENERATE(from_range(variants())));
  INFO("backend " << name);
  const Tolerances& tol = tolerancesFor(name);
  // 30 polydisperse spheres on a loose lattice between walls 3 apart, settled under gravity.
  core::SystemDef s = boxSystem(5.0, 3.0, false, 0.0);
  core::Rng rng(21, core::StreamId::Test);
  double weight = 0.0;
  for (int k = 0; k < 30; ++k) {
    const int ix = k % 4, iy = (k / 4) % 2, iz = k / 8;
    const double d = rng.uniform(0.85, 1.05);
    const Vec3 p(0.6 + 1.25 * ix + rng.uniform(-0.05, 0.05), 0.75 + 1.5 * iy + rng.uniform(-0.1, 0.1),
                 0.55 + 1.07 * iz + rng.uniform(0.0, 0.02));
    s.grains.push_back(sphere(d, p));
    weight += sphereMass(d);
  }
  const auto backend = makeVariant(name, s, tol.tightOptions);
  // Frictionless spheres keep rearranging for a while (20 to 40 t0 here, depending on the
  // trajectory): step until the pile is at rest, with a cap.
  const double dt = 2e-3;
  double kinetic = 1e300;
  int steps = 0;
  for (; steps < 30000 && kinetic > tol.restKinetic * weight; ++steps) {
    backend->step(dt);
    if (steps % 250 != 0) continue;
    kinetic = 0.0;
    for (std::size_t i = 0; i < s.grains.size(); ++i)
      kinetic += 0.5 * sphereMass(s.grains[i].size) * backend->states()[i].velocity.squaredNorm();
  }
  INFO("kinetic energy " << kinetic << " after " << steps << " steps");
  REQUIRE(kinetic <= tol.restKinetic * weight);
  backend->step(dt);
  const Vec3 floor = wallForce(backend->contacts(), core::WallId::Floor);
  CHECK(-floor.z() == Approx(weight).epsilon(tol.floorReactionRel));
  bool sideContacts = false;
  for (const core::Contact& c : backend->contacts()) {
    if (c.b != static_cast<int>(core::WallId::SideLow) && c.b != static_cast<int>(core::WallId::SideHigh)) continue;
    sideContacts = true;
    CHECK(std::abs(c.forceOnB().z()) <= 1e-12 * weight);
    CHECK(std::abs(c.forceOnB().x()) <= 1e-12 * weight);
  }
  CHECK(sideContacts);
}

TEST_CASE("a sphere on a frictional side wall rolls below the Coulomb limit and slides above it", "[conformance]") {
  const std::string name(GENERATE(from_range(variants())));
  // Body force per unit mass (0, -Fn, -Ft): Fn presses the sphere into the wall y = 0, Ft pulls it
  // down along the wall; the floor is far below. A free sphere does not stick: like a ball on an
  // incline it rolls without slipping with a = Ft / (1 + I/(m r^2)) = (5/7) Ft, which needs the
  // friction f = (2/7) m Ft <= mu m Fn; above that limit it slides with a = Ft - mu Fn.
  const double mu = 0.5, fn = 1.0;
  const double ft = GENERATE(0.5, 1.5, 2.5);
  const bool rolls = 2.0 / 7.0 * ft <= mu * fn;
  const double expected = rolls ? 5.0 / 7.0 * ft : ft - mu * fn;
  INFO("backend " << name << ", Ft/Fn " << ft / fn << (rolls ? " (rolls)" : " (slides)"));
  const Tolerances& tol = tolerancesFor(name);
  core::SystemDef s = boxSystem(20.0, 10.0, false, mu);
  s.gravity = Vec3(0.0, -fn, -ft);
  s.grains.push_back(sphere(1.0, Vec3(10.0, 0.5, 5.0)));
  const auto backend = makeVariant(name, s, tol.options);
  const double dt = 1e-3;
  const int steps = 400;
  for (int k = 0; k < steps; ++k) backend->step(dt);
  const core::BodyState& b = backend->states()[0];
  const double t = steps * dt;
  CHECK(-b.velocity.z() == Approx(expected * t).epsilon(tol.wallAccelerationRel));
  CHECK(std::abs(b.velocity.y()) < 1e-9);
  CHECK(std::abs(b.position.y() - 0.5) < 1e-6);
  // Rolling without slipping: the contact point is at rest, v_z = -r w_x... (w along -x for a
  // sphere rolling down the wall y = 0: v_contact = v + w x (-r e_y)).
  const Vec3 vContact = b.velocity + b.angularVelocity.cross(Vec3(0.0, -0.5, 0.0));
  if (rolls)
    CHECK(vContact.norm() < 1e-6 * expected * t);
  else
    CHECK(vContact.norm() > 0.1 * expected * t);
  // The reported wall force: normal m Fn, tangential friction (2/7) m Ft or mu m Fn, upwards on the
  // sphere, i.e. downwards on the wall.
  const double m = sphereMass(1.0);
  const Vec3 f = wallForce(backend->contacts(), core::WallId::SideLow);
  CHECK(-f.y() == Approx(m * fn).epsilon(tol.wallAccelerationRel));
  CHECK(-f.z() == Approx(m * (ft - expected)).epsilon(tol.wallAccelerationRel));
}

TEST_CASE("a contact across the periodic boundaries is the same contact as in the interior", "[conformance]") {
  const std::string name(GENERATE(from_range(variants())));
  INFO("backend " << name);
  const Tolerances& tol = tolerancesFor(name);
  // Sphere A on the floor, sphere B leaning on it, the pair tilted in x and y. Once across the
  // corner x = 0 / y = 0 of a biperiodic box, once in the middle.
  auto run = [&](const Vec3& origin, std::vector<Vec3>& relative, std::vector<double>& forces) {
    core::SystemDef s = boxSystem(20.0, 20.0, true, 0.0);
    const Vec3 offset(0.42, 0.42, std::sqrt(1.0 - 2.0 * 0.42 * 0.42));  // |offset| = 1 = d
    s.grains.push_back(sphere(1.0, origin + Vec3(0.0, 0.0, 0.5)));
    s.grains.push_back(sphere(1.0, origin + Vec3(0.0, 0.0, 0.5) + offset));
    const auto backend = makeVariant(name, s, tol.tightOptions);  // converged: compare physics, not round-off
    for (int k = 0; k < 50; ++k) backend->step(1e-3);
    const core::BoxDef& box = s.box;
    relative = {box.minimumImage(backend->states()[1].position - backend->states()[0].position),
                backend->states()[0].velocity, backend->states()[1].velocity};
    forces.clear();
    for (const core::Contact& c : backend->contacts()) forces.push_back(c.normalForce());
    std::sort(forces.begin(), forces.end());
    for (const auto& st : backend->states()) {
      CHECK(st.position.x() >= 0.0);
      CHECK(st.position.x() < box.lengthX);
      CHECK(st.position.y() >= 0.0);
      CHECK(st.position.y() < box.width);
    }
  };
  std::vector<Vec3> relEdge, relMid;
  std::vector<double> fEdge, fMid;
  run(Vec3(19.8, 19.8, 0.0), relEdge, fEdge);
  run(Vec3(10.0, 10.0, 0.0), relMid, fMid);
  REQUIRE(fEdge.size() == fMid.size());
  REQUIRE(fEdge.size() >= 2);  // floor-A and A-B at least
  for (std::size_t i = 0; i < fEdge.size(); ++i) CHECK(std::abs(fEdge[i] - fMid[i]) < tol.periodicAbs);
  for (std::size_t i = 0; i < relEdge.size(); ++i) CHECK((relEdge[i] - relMid[i]).norm() < tol.periodicAbs);
  // The pair really is in contact and pushes: B slides off A, so the A-B force is positive.
  CHECK(fEdge.back() > 0.0);
}
