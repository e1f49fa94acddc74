// The bullet backend (docs/model.md, "Bullet: sequential impulses"): Bullet's
// btDiscreteDynamicsWorld and btSequentialImpulseConstraintSolver (double precision) behind
// core::ContactBackend.
//
// What Bullet supplies: shapes (btSphereShape, btConvexHullShape of the pinacoid's 8 vertices,
// btStaticPlaneShape walls), the broad phase (btDbvtBroadphase), the narrow phase (GJK/EPA,
// polyhedral SAT and face clipping, multipoint plane contacts), persistent manifolds, the
// sequential-impulse solver with split impulse, and the time integration.
//
// What this file adds, because Bullet has no notion of it:
// - Periodic boundaries. Bullet's broad phase only sees grains where they are. Pairs across a
//   periodic face are found by PeriodicPairFinder; their contacts are computed by the same
//   collision algorithms Bullet would use (dispatcher->findAlgorithm) with grain b moved by the
//   period for the duration of the narrow phase, into manifolds we own. Before the solve, the
//   point on b is moved back by the period: the solver's lever arm is point - origin of the REAL
//   body b, so the impulse lands on the real grains (Bullet's createPredictiveContacts injects
//   its own manifolds in the same way). No ghost bodies: an image is never a solver body.
// - One solve over everything. A settling pile is one island, so instead of Bullet's island
//   manager we hand the solver all manifolds (broad-phase and periodic) in one group, sorted by
//   grain pair so that the Gauss-Seidel row order does not depend on where a contact came from.
// - The material rule of the model: grain-grain friction 0, side walls mu_w, floor 0, restitution 0
//   (Bullet would multiply the two bodies' coefficients), installed as gContactAddedCallback.
// - The step as named phases (core::Phase), Bullet's own pieces called one by one by step() and
//   timed there by one core::PhaseClock.
#include "backends/bullet/bullet_backend.hpp"

#include <btBulletCollisionCommon.h>
#include <btBulletDynamicsCommon.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "backends/bullet/bullet_settings.hpp"
#include "backends/bullet/periodic_pairs.hpp"

namespace confpack::bullet {

namespace {

using core::Phase;
using core::Vec3;

btVector3 toBt(const Vec3& v) {
  return {v.x(), v.y(), v.z()};
}
Vec3 fromBt(const btVector3& v) {
  return {v.x(), v.y(), v.z()};
}

// ---- Material rule ---------------------------------------------------------------------------
// Grains carry their index as user index (>= 0), walls their negative WallId and their own
// friction coefficient in m_friction. The model: grain-grain frictionless, side walls mu_w, floor
// frictionless (its m_friction is 0), restitution 0 everywhere, no rolling or spinning friction.
double combinedFrictionOf(const btCollisionObject* o0, const btCollisionObject* o1) {
  const bool wall0 = o0->getUserIndex() < 0, wall1 = o1->getUserIndex() < 0;
  if (wall0 && !wall1) return o0->getFriction();
  if (wall1 && !wall0) return o1->getFriction();
  return 0.0;
}

// Called by btManifoldResult::addContactPoint for every point it adds or replaces when either
// body has CF_CUSTOM_MATERIAL_CALLBACK (all grains have it). Stateless, so one global pointer
// serves every backend instance.
bool applyMaterialRule(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int, int,
                       const btCollisionObjectWrapper* w1, int, int) {
  cp.m_combinedFriction = combinedFrictionOf(w0->getCollisionObject(), w1->getCollisionObject());
  cp.m_combinedRestitution = 0.0;
  cp.m_combinedRollingFriction = 0.0;
  cp.m_combinedSpinningFriction = 0.0;
  return true;
}

// ---- Bullet subclasses -----------------------------------------------------------------------

// Every manifold gets our contact breaking threshold (Bullet's default is a global, scaled by
// each shape's size).
class Dispatcher final : public btCollisionDispatcher {
 public:
  Dispatcher(btCollisionConfiguration* config, double breakingThreshold)
      : btCollisionDispatcher(config), breakingThreshold_(breakingThreshold) {}
  btPersistentManifold* getNewManifold(const btCollisionObject* b0, const btCollisionObject* b1) override {
    btPersistentManifold* m = btCollisionDispatcher::getNewManifold(b0, b1);
    m->setContactBreakingThreshold(breakingThreshold_);
    return m;
  }

 private:
  double breakingThreshold_;
};

// The sequential-impulse solver with its three stages callable one by one, and one saving:
// Bullet gives every contact point one or two friction rows whatever its friction coefficient.
// With mu = 0 (grain-grain and floor contacts, i.e. nearly all of a pile) a friction row is
// clamped to [-0, 0] in every sweep, so it never applies an impulse and contributes nothing to
// the residual: the row is pure cost (two thirds of all rows with two friction directions).
// When `skipZeroFriction` is set, manifolds whose points all have zero combined friction get
// normal rows only, built by Bullet's own setupContactConstraint; the physics is bitwise the
// same (tested), a step of a 163-sphere pile about 1.5 times faster (measured).
class PhasedSolver final : public btSequentialImpulseConstraintSolver {
 public:
  bool skipZeroFriction = true;
  /// Largest velocity correction of the last sweep [sqrt(g d_L)]: Bullet's residual is the max
  /// over rows of (delta impulse / jacDiagABInv)^2, a squared velocity.
  double residual() const { return std::sqrt(std::max(0.0, double(m_leastSquaresResidual))); }
  int iterationsUsed() const { return m_analyticsData.m_numIterationsUsed; }

  // Bullet's solveGroup is these three calls in this order (no constraints, no debug drawer);
  // step() makes them one by one, a phase each.
  /// Solver bodies and rows, and the warm-start impulses (Bullet does both in one loop).
  void prepare(btCollisionObject** bodies, int numBodies, btPersistentManifold** manifolds, int numManifolds,
               const btContactSolverInfo& info) {
    solveGroupCacheFriendlySetup(bodies, numBodies, manifolds, numManifolds, nullptr, 0, info, nullptr);
  }
  /// Split-impulse (position) sweeps, then velocity sweeps.
  void iterate(btCollisionObject** bodies, int numBodies, btPersistentManifold** manifolds, int numManifolds,
               const btContactSolverInfo& info) {
    solveGroupCacheFriendlyIterations(bodies, numBodies, manifolds, numManifolds, nullptr, 0, info, nullptr);
  }
  /// Impulses into the manifold points, velocities into the bodies.
  void finish(btCollisionObject** bodies, int numBodies, const btContactSolverInfo& info) {
    solveGroupCacheFriendlyFinish(bodies, numBodies, info);
  }

 protected:
  void convertContacts(btPersistentManifold** manifolds, int numManifolds, const btContactSolverInfo& info) override {
    for (int i = 0; i < numManifolds; ++i) {
      btPersistentManifold* m = manifolds[i];
      bool frictionless = skipZeroFriction;
      for (int k = 0; frictionless && k < m->getNumContacts(); ++k)
        frictionless =
            m->getContactPoint(k).m_combinedFriction == 0.0 && m->getContactPoint(k).m_combinedRollingFriction == 0.0;
      if (frictionless)
        convertFrictionlessContact(m, info);
      else
        convertContact(m, info);
    }
  }

  // btSequentialImpulseConstraintSolver::convertContact without the friction rows.
  void convertFrictionlessContact(btPersistentManifold* manifold, const btContactSolverInfo& info) {
    auto* o0 = const_cast<btCollisionObject*>(manifold->getBody0());
    auto* o1 = const_cast<btCollisionObject*>(manifold->getBody1());
    const int idA = getOrInitSolverBody(*o0, info.m_timeStep);
    const int idB = getOrInitSolverBody(*o1, info.m_timeStep);
    if (m_tmpSolverBodyPool[idA].m_invMass.fuzzyZero() && m_tmpSolverBodyPool[idB].m_invMass.fuzzyZero()) return;
    for (int k = 0; k < manifold->getNumContacts(); ++k) {
      btManifoldPoint& cp = manifold->getContactPoint(k);
      if (cp.getDistance() > manifold->getContactProcessingThreshold()) continue;
      btSolverConstraint& row = m_tmpSolverContactConstraintPool.expandNonInitializing();
      row.m_solverBodyIdA = idA;
      row.m_solverBodyIdB = idB;
      row.m_originalContactPoint = &cp;
      const btVector3 relPos1 = cp.getPositionWorldOnA() - o0->getWorldTransform().getOrigin();
      const btVector3 relPos2 = cp.getPositionWorldOnB() - o1->getWorldTransform().getOrigin();
      btScalar relaxation;
      setupContactConstraint(row, idA, idB, cp, info, relaxation, relPos1, relPos2);
      row.m_frictionIndex = -1;  // no friction rows (read in solveGroupCacheFriendlyFinish)
    }
  }

  btScalar solveGroupCacheFriendlyIterations(btCollisionObject** bodies, int numBodies,
                                             btPersistentManifold** manifolds, int numManifolds,
                                             btTypedConstraint** constraints, int numConstraints,
                                             const btContactSolverInfo& info, btIDebugDraw* debugDrawer) override {
    m_leastSquaresResidual = 0.0;
    m_analyticsData.m_numIterationsUsed = 0;
    const btScalar r = btSequentialImpulseConstraintSolver::solveGroupCacheFriendlyIterations(
        bodies, numBodies, manifolds, numManifolds, constraints, numConstraints, info, debugDrawer);
    return r;
  }
  btScalar solveGroupCacheFriendlyFinish(btCollisionObject** bodies, int numBodies,
                                         const btContactSolverInfo& info) override {
    // Impulses into the manifold points (next step's warm start, and what readContacts reports),
    // then Bullet's own write-back of velocities and split-impulse pushes. Bullet's
    // writeBackContacts would read the friction rows of every contact, which frictionless
    // rows do not have, so the contact part is done here and Bullet's is switched off.
    const bool twoDirections = (info.m_solverMode & SOLVER_USE_2_FRICTION_DIRECTIONS) != 0;
    for (int j = 0; j < m_tmpSolverContactConstraintPool.size(); ++j) {
      const btSolverConstraint& row = m_tmpSolverContactConstraintPool[j];
      auto* pt = static_cast<btManifoldPoint*>(row.m_originalContactPoint);
      pt->m_appliedImpulse = row.m_appliedImpulse;
      pt->m_appliedImpulseLateral1 = 0.0;
      pt->m_appliedImpulseLateral2 = 0.0;
      if (row.m_frictionIndex >= 0) {
        pt->m_appliedImpulseLateral1 = m_tmpSolverContactFrictionConstraintPool[row.m_frictionIndex].m_appliedImpulse;
        if (twoDirections)
          pt->m_appliedImpulseLateral2 =
              m_tmpSolverContactFrictionConstraintPool[row.m_frictionIndex + 1].m_appliedImpulse;
      }
    }
    btContactSolverInfo rest = info;
    rest.m_solverMode &= ~SOLVER_USE_WARMSTARTING;
    return btSequentialImpulseConstraintSolver::solveGroupCacheFriendlyFinish(bodies, numBodies, rest);
  }
};

// Sphere-sphere contacts. Bullet's btSphereSphereCollisionAlgorithm clears its manifold on
// every call (CLEAR_MANIFOLD: "don't do this, it disables warmstarting"), creates a contact only
// once the spheres overlap, and ignores a shared manifold. A dense sphere pile needs warm
// starting (the static forces of a deep pile take many sweeps to build), contacts from a small
// gap on (so that an approaching pair is stopped at the surface instead of after overlapping),
// and periodic pairs need their own manifold. This algorithm keeps the one point of the pair
// and carries its impulses over from step to step.
class SphereSphereAlgorithm final : public btActivatingCollisionAlgorithm {
 public:
  SphereSphereAlgorithm(btPersistentManifold* shared, const btCollisionAlgorithmConstructionInfo& ci,
                        const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1)
      : btActivatingCollisionAlgorithm(ci, w0, w1), manifold_(shared) {
    if (!manifold_) {
      manifold_ = m_dispatcher->getNewManifold(w0->getCollisionObject(), w1->getCollisionObject());
      own_ = true;
    }
  }
  ~SphereSphereAlgorithm() override {
    if (own_) m_dispatcher->releaseManifold(manifold_);
  }

  void processCollision(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1, const btDispatcherInfo&,
                        btManifoldResult* result) override {
    result->setPersistentManifold(manifold_);
    const double r0 = static_cast<const btSphereShape*>(w0->getCollisionShape())->getRadius();
    const double r1 = static_cast<const btSphereShape*>(w1->getCollisionShape())->getRadius();
    const btVector3 diff = w0->getWorldTransform().getOrigin() - w1->getWorldTransform().getOrigin();
    const double len = diff.length();
    const double gap = len - (r0 + r1);
    // Impulses of the pair's single point, kept across the rebuild below.
    double normal = 0.0, lateral1 = 0.0, lateral2 = 0.0;
    const bool had = manifold_->getNumContacts() > 0;
    if (had) {
      const btManifoldPoint& old = manifold_->getContactPoint(0);
      normal = old.m_appliedImpulse;
      lateral1 = old.m_appliedImpulseLateral1;
      lateral2 = old.m_appliedImpulseLateral2;
    }
    // Rebuilt every step (the contact point of two spheres moves with both bodies, so Bullet's
    // point matching in a body frame would keep stale points), impulses restored.
    manifold_->clearManifold();
    if (gap >= manifold_->getContactBreakingThreshold() || len <= SIMD_EPSILON) return;
    const btVector3 normalOnB = diff / len;  // from sphere 1 towards sphere 0
    const btVector3 pointOnB = w1->getWorldTransform().getOrigin() + r1 * normalOnB;
    result->addContactPoint(normalOnB, pointOnB, gap);
    if (had && manifold_->getNumContacts() == 1) {
      btManifoldPoint& p = manifold_->getContactPoint(0);
      p.m_appliedImpulse = normal;
      p.m_appliedImpulseLateral1 = lateral1;
      p.m_appliedImpulseLateral2 = lateral2;
    }
  }
  btScalar calculateTimeOfImpact(btCollisionObject*, btCollisionObject*, const btDispatcherInfo&,
                                 btManifoldResult*) override {
    return 1.0;  // no continuous collision detection
  }
  void getAllContactManifolds(btManifoldArray& out) override {
    if (own_) out.push_back(manifold_);
  }

  struct CreateFunc final : public btCollisionAlgorithmCreateFunc {
    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1) override {
      void* mem = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(SphereSphereAlgorithm));
      return new (mem) SphereSphereAlgorithm(ci.m_manifold, ci, w0, w1);
    }
  };

 private:
  btPersistentManifold* manifold_ = nullptr;
  bool own_ = false;
};

// The world, with access to the protected pieces of internalSingleStepSimulation so that
// step() can call them one by one (and time them) and put its own manifolds into the solve.
class World final : public btDiscreteDynamicsWorld {
 public:
  using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;

  void predict(double dt) { predictUnconstraintMotion(dt); }
  void integrate(double dt) { integrateTransforms(dt); }

  /// Bullet's updateAabbs inflates every box by the global gContactBreakingThreshold; ours use
  /// the configured threshold so that the broad phase keeps every pair the narrow phase could
  /// turn into a contact. Static walls keep the boxes they got when added.
  void updateGrainAabbs(double inflation) {
    const btVector3 pad(inflation, inflation, inflation);
    for (int i = 0; i < m_collisionObjects.size(); ++i) {
      btCollisionObject* o = m_collisionObjects[i];
      if (o->isStaticObject()) continue;
      btVector3 lo, hi;
      o->getCollisionShape()->getAabb(o->getWorldTransform(), lo, hi);
      m_broadphasePairCache->setAabb(o->getBroadphaseHandle(), lo - pad, hi + pad, m_dispatcher1);
    }
  }
};

// A contact across a periodic face: its own manifold (body0 = grain a, body1 = grain b, points
// on b expressed for the real b) and the collision algorithm Bullet picked for the two shapes.
struct PeriodicContact {
  std::unique_ptr<btPersistentManifold> manifold;
  btCollisionAlgorithm* algorithm = nullptr;
  Vec3 shift = Vec3::Zero();  ///< b's image is at b + shift [d_L]
  bool alive = false;         ///< found by this step's pair search
};

using PeriodicKey = std::tuple<int, int, int, int>;  // a, b, shiftX, shiftY

// ---- The backend -----------------------------------------------------------------------------

class BulletBackend final : public core::ContactBackend {
 public:
  BulletBackend(const core::SystemDef& system, const BulletSettings& settings);
  ~BulletBackend() override;

  std::string_view name() const override { return "bullet"; }
  void step(double dt) override;
  void restoreState(const nlohmann::json& state) override;
  const std::vector<core::BodyState>& states() const override { return states_; }
  const std::vector<core::Contact>& contacts() const override { return contacts_; }
  const core::StepProfile& profile() const override { return profile_; }
  nlohmann::json settings() const override {
    nlohmann::json j = settings_;
    return j;
  }

  // inspect:: hooks
  std::vector<Vec3> supportPoints(int grain, const std::vector<Vec3>& dirs) const;
  std::vector<double> combinedFriction(int a, int b) const;
  double collisionMargin(int grain) const;

 private:
  void buildWorld();
  // The phases of step(), in its order.
  void beginStep(double dt);
  void applyForces(double dt);
  void updatePairs();
  void collide();
  void prepareContacts();
  void solveContacts();
  void storeImpulses();
  void integrate(double dt);
  void readContacts(double dt);
  void wrapIntoBox();
  void readStates();
  // Their parts.
  void findPeriodicPairs();
  void collidePeriodicPairs();
  void gatherManifolds();

  core::SystemDef system_;
  BulletSettings settings_;
  double dt_ = 0.0;

  // Declaration order = reverse destruction order: the world goes first (it removes the
  // bodies' broad-phase proxies), then bodies and shapes, then the machinery.
  std::unique_ptr<btDefaultCollisionConfiguration> config_;
  SphereSphereAlgorithm::CreateFunc sphereSphere_;  ///< outlives the dispatcher that points to it
  std::unique_ptr<Dispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<PhasedSolver> solver_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btRigidBody>> grains_;  ///< index = grain index
  std::vector<std::unique_ptr<btRigidBody>> walls_;
  std::unique_ptr<World> world_;

  std::unique_ptr<PeriodicPairFinder> pairFinder_;
  std::map<PeriodicKey, PeriodicContact> periodic_;
  std::vector<double> boundingRadii_;
  std::vector<btCollisionObject*> grainObjects_;
  std::vector<btPersistentManifold*> solved_;  ///< manifolds of the last solve, sorted by pair

  std::vector<core::BodyState> states_;
  std::vector<core::Contact> contacts_;
  core::StepProfile profile_;
};

BulletBackend::BulletBackend(const core::SystemDef& system, const BulletSettings& settings)
    : system_(system), settings_(settings) {
  system_.box.validate();
  if (!(system_.density > 0.0) || !std::isfinite(system_.density))
    throw std::invalid_argument(fmt::format("system: density must be a positive number (got {})", system_.density));
  if (!system_.gravity.allFinite()) throw std::invalid_argument("system: gravity must be finite");
  double maxRadius = 0.0;
  for (std::size_t i = 0; i < system_.grains.size(); ++i) {
    const core::Grain& g = system_.grains[i];
    if (!(g.size > 0.0) || !std::isfinite(g.size))
      throw std::invalid_argument(fmt::format("grain {}: size must be a positive number (got {})", i, g.size));
    if (!g.position.allFinite()) throw std::invalid_argument(fmt::format("grain {}: position must be finite", i));
    if (!g.orientation.coeffs().allFinite() || g.orientation.norm() < 1e-12)
      throw std::invalid_argument(fmt::format("grain {}: orientation must be a non-zero quaternion", i));
    if (g.shape == core::ShapeKind::Pinacoid) g.params.validate();
    boundingRadii_.push_back(g.boundingRadius());
    maxRadius = std::max(maxRadius, boundingRadii_.back());
  }
  pairFinder_ = std::make_unique<PeriodicPairFinder>(system_.box, 2.0 * maxRadius + settings_.contactBreakingThreshold);
  buildWorld();
  readStates();
}

BulletBackend::~BulletBackend() {
  // Our periodic algorithms came from the dispatcher's pool; give them back before it goes.
  for (auto& [key, pc] : periodic_) {
    if (pc.algorithm) {
      pc.algorithm->~btCollisionAlgorithm();
      dispatcher_->freeCollisionAlgorithm(pc.algorithm);
    }
  }
  periodic_.clear();
  world_.reset();
}

void BulletBackend::buildWorld() {
  const std::size_t n = system_.grains.size();
  btDefaultCollisionConstructionInfo ci;
  // Pools sized for the dense pile: a few manifolds (and their algorithms) per grain; beyond
  // that Bullet falls back to the heap.
  const int pool = std::max<int>(4096, static_cast<int>(n) * settings_.manifoldsPerGrain);
  ci.m_defaultMaxPersistentManifoldPoolSize = pool;
  ci.m_defaultMaxCollisionAlgorithmPoolSize = 2 * pool;
  config_ = std::make_unique<btDefaultCollisionConfiguration>(ci);
  // Multipoint wall contacts for polyhedra (see BulletSettings::planePerturbationIterations).
  config_->setPlaneConvexMultipointIterations(settings_.planePerturbationIterations,
                                              settings_.planePerturbationMinPoints);
  dispatcher_ = std::make_unique<Dispatcher>(config_.get(), settings_.contactBreakingThreshold);
  dispatcher_->registerCollisionCreateFunc(SPHERE_SHAPE_PROXYTYPE, SPHERE_SHAPE_PROXYTYPE, &sphereSphere_);
  broadphase_ = std::make_unique<btDbvtBroadphase>();
  solver_ = std::make_unique<PhasedSolver>();
  solver_->skipZeroFriction = settings_.skipZeroFrictionRows;
  world_ = std::make_unique<World>(dispatcher_.get(), broadphase_.get(), solver_.get(), config_.get());
  world_->setGravity(toBt(system_.gravity));

  btContactSolverInfo& info = world_->getSolverInfo();
  info.m_numIterations = settings_.iterations;
  info.m_splitImpulse = settings_.splitImpulse ? 1 : 0;
  info.m_splitImpulsePenetrationThreshold = settings_.splitImpulsePenetrationThreshold;
  info.m_splitImpulseTurnErp = settings_.splitImpulseTurnErp;
  info.m_erp = settings_.erp;
  info.m_erp2 = settings_.erp2;
  info.m_globalCfm = settings_.globalCfm;
  info.m_sor = settings_.sor;
  info.m_linearSlop = settings_.linearSlop;
  info.m_warmstartingFactor = settings_.warmStartingFactor;
  info.m_restitution = 0.0;
  info.m_friction = 0.0;
  // Warm starting stays on: it is also what makes the solver write the impulses back into the
  // manifold points, where readContacts() finds them (a factor of 0 disables the warm start itself).
  info.m_solverMode = SOLVER_USE_WARMSTARTING | SOLVER_SIMD;
  if (settings_.frictionDirections == 2) info.m_solverMode |= SOLVER_USE_2_FRICTION_DIRECTIONS;
  if (settings_.randomizeOrder) info.m_solverMode |= SOLVER_RANDMIZE_ORDER;

  btDispatcherInfo& dispatch = world_->getDispatchInfo();
  dispatch.m_enableSatConvex = settings_.satConvex;
  dispatch.m_useContinuous = false;  // no CCD: a grain moves < d/100 per step (docs/model.md, "Time step")

  gContactAddedCallback = &applyMaterialRule;

  // Grains, in index order (the broad phase orders a pair's bodies by insertion, so body0 of
  // an interior manifold is the lower grain index, as for the periodic ones).
  for (std::size_t i = 0; i < n; ++i) {
    const core::Grain& g = system_.grains[i];
    std::unique_ptr<btCollisionShape> shape;
    if (g.shape == core::ShapeKind::Sphere) {
      // A sphere is a point with margin = radius: its support points are exact.
      shape = std::make_unique<btSphereShape>(0.5 * g.size);
    } else {
      const core::ConvexPolyhedron poly = g.polyhedron();  // centroid at the origin, principal axes
      auto hull = std::make_unique<btConvexHullShape>();
      for (const Vec3& v : poly.vertices()) hull->addPoint(toBt(v), false);
      // Bullet adds a hull's margin outward (support = vertex + margin * direction); with a
      // margin the grain would be a rounded, inflated pinacoid. Zero margin keeps the shape
      // exact; Bullet's hull-hull contacts then come from SAT and face clipping, which do not
      // need a margin.
      hull->setMargin(0.0);
      hull->recalcLocalAabb();
      hull->initializePolyhedralFeatures();
      shape = std::move(hull);
    }
    // Exact mass properties from core (Bullet's calculateLocalInertia would use the AABB box).
    const double mass = system_.density * g.volume();
    const core::Mat3 inertia = g.bodyInertia(system_.density);
    btRigidBody::btRigidBodyConstructionInfo rbci(mass, nullptr, shape.get(),
                                                  btVector3(inertia(0, 0), inertia(1, 1), inertia(2, 2)));
    const Vec3 p = system_.box.wrap(g.position);
    const core::Quat q = g.orientation.normalized();
    rbci.m_startWorldTransform = btTransform(btQuaternion(q.x(), q.y(), q.z(), q.w()), toBt(p));
    rbci.m_friction = 0.0;
    rbci.m_restitution = 0.0;
    rbci.m_rollingFriction = 0.0;
    rbci.m_spinningFriction = 0.0;
    rbci.m_linearDamping = 0.0;
    rbci.m_angularDamping = 0.0;
    auto body = std::make_unique<btRigidBody>(rbci);
    body->setUserIndex(static_cast<int>(i));
    body->setActivationState(DISABLE_DEACTIVATION);
    body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    world_->addRigidBody(body.get());
    grainObjects_.push_back(body.get());
    shapes_.push_back(std::move(shape));
    grains_.push_back(std::move(body));
  }

  // Walls: static planes n.x = c, n pointing into the box.
  auto addWall = [&](core::WallId id) {
    const Vec3 nrm = core::BoxDef::wallNormal(id);
    const double c = nrm.dot(system_.box.wallPoint(id));
    auto shape = std::make_unique<btStaticPlaneShape>(toBt(nrm), c);
    btRigidBody::btRigidBodyConstructionInfo rbci(0.0, nullptr, shape.get());
    rbci.m_friction = system_.walls.frictionOf(id);
    rbci.m_restitution = 0.0;
    auto body = std::make_unique<btRigidBody>(rbci);
    body->setUserIndex(static_cast<int>(id));
    world_->addRigidBody(body.get());
    shapes_.push_back(std::move(shape));
    walls_.push_back(std::move(body));
  };
  addWall(core::WallId::Floor);
  if (!system_.box.periodicY) {
    addWall(core::WallId::SideLow);
    addWall(core::WallId::SideHigh);
  }
}

void BulletBackend::findPeriodicPairs() {
  std::vector<Vec3> positions(grains_.size());
  for (std::size_t i = 0; i < grains_.size(); ++i) positions[i] = fromBt(grains_[i]->getWorldTransform().getOrigin());
  for (auto& [key, pc] : periodic_) pc.alive = false;
  for (const ImagePair& p : pairFinder_->find(positions, boundingRadii_, settings_.contactBreakingThreshold)) {
    PeriodicContact& pc = periodic_[{p.a, p.b, p.shiftX, p.shiftY}];
    pc.alive = true;
    if (!pc.manifold) {
      pc.shift = p.shift;
      pc.manifold = std::make_unique<btPersistentManifold>(grains_[p.a].get(), grains_[p.b].get(), 0,
                                                           settings_.contactBreakingThreshold, BT_LARGE_FLOAT);
    }
  }
  // Pairs out of reach: drop their manifold and algorithm, as Bullet does when a broad-phase
  // pair ends.
  for (auto it = periodic_.begin(); it != periodic_.end();) {
    if (!it->second.alive) {
      if (it->second.algorithm) {
        it->second.algorithm->~btCollisionAlgorithm();
        dispatcher_->freeCollisionAlgorithm(it->second.algorithm);
      }
      it = periodic_.erase(it);
    } else {
      ++it;
    }
  }
}

void BulletBackend::collidePeriodicPairs() {
  const btDispatcherInfo& dispatch = world_->getDispatchInfo();
  for (auto& [key, pc] : periodic_) {
    btRigidBody* a = grains_[std::get<0>(key)].get();
    btRigidBody* b = grains_[std::get<1>(key)].get();
    // Move b onto its image for the narrow phase only: every collision algorithm (and
    // btManifoldResult, which reads the objects' transforms, not the wrappers') then sees one
    // consistent pair, and the local contact points on b are b's body-frame points.
    const btTransform real = b->getWorldTransform();
    btTransform image = real;
    image.getOrigin() += toBt(pc.shift);
    b->setWorldTransform(image);
    btCollisionObjectWrapper wa(nullptr, a->getCollisionShape(), a, a->getWorldTransform(), -1, -1);
    btCollisionObjectWrapper wb(nullptr, b->getCollisionShape(), b, b->getWorldTransform(), -1, -1);
    if (!pc.algorithm)
      pc.algorithm = dispatcher_->findAlgorithm(&wa, &wb, pc.manifold.get(), BT_CONTACT_POINT_ALGORITHMS);
    btManifoldResult result(&wa, &wb);
    result.setPersistentManifold(pc.manifold.get());
    pc.algorithm->processCollision(&wa, &wb, dispatch, &result);
    // What an algorithm does with a manifold it owns: update the cached points and drop those
    // that separated or slid beyond the breaking threshold.
    pc.manifold->refreshContactPoints(a->getWorldTransform(), image);
    b->setWorldTransform(real);
    // The solver's lever arm on b is positionWorldOnB - origin(b): express the point for the
    // real b.
    const btVector3 back = toBt(-pc.shift);
    for (int k = 0; k < pc.manifold->getNumContacts(); ++k) pc.manifold->getContactPoint(k).m_positionWorldOnB += back;
  }
}

void BulletBackend::gatherManifolds() {
  // All manifolds with points, broad-phase and periodic, in one group sorted by grain pair (the
  // solve order then does not depend on where a contact was found).
  solved_.clear();
  btDispatcher* d = world_->getDispatcher();
  for (int i = 0; i < d->getNumManifolds(); ++i) {
    btPersistentManifold* m = d->getManifoldByIndexInternal(i);
    if (m->getNumContacts() > 0) solved_.push_back(m);
  }
  for (auto& [key, pc] : periodic_)
    if (pc.manifold->getNumContacts() > 0) solved_.push_back(pc.manifold.get());
  auto pairOf = [](const btPersistentManifold* m) {
    const int i0 = m->getBody0()->getUserIndex(), i1 = m->getBody1()->getUserIndex();
    const int a = i0 < 0 ? i1 : (i1 < 0 ? i0 : std::min(i0, i1));
    const int b = i0 < 0 ? i0 : (i1 < 0 ? i1 : std::max(i0, i1));
    return std::make_pair(a, b);
  };
  std::stable_sort(solved_.begin(), solved_.end(),
                   [&](const btPersistentManifold* x, const btPersistentManifold* y) { return pairOf(x) < pairOf(y); });
}

void BulletBackend::wrapIntoBox() {
  std::vector<btRigidBody*> jumped;
  std::map<int, Vec3> jumps;  // grain -> its jump by whole periods
  for (auto& body : grains_) {
    btTransform t = body->getWorldTransform();
    const Vec3 p = fromBt(t.getOrigin());
    const Vec3 w = system_.box.wrap(p);
    if (w == p) continue;
    t.setOrigin(toBt(w));
    body->setWorldTransform(t);
    body->setInterpolationWorldTransform(t);
    jumped.push_back(body.get());
    jumps[body->getUserIndex()] = w - p;
  }
  if (jumped.empty()) return;
  // The contacts were read before the wrap: keep their points near grain a's reported position.
  for (core::Contact& c : contacts_)
    if (auto it = jumps.find(c.a); it != jumps.end())
      for (core::ContactPoint& p : c.points) p.position += it->second;
  // A grain that jumped by a period leaves the cached points of its broad-phase manifolds joining
  // anchors a period apart. Bullet would keep a point whose anchors are separated along the
  // normal (it only drops points that open up or slide), i.e. a bogus overlap of a whole period,
  // and the broad phase (btDbvtBroadphase) removes stale pairs only a few per step. Drop the
  // grain's pair algorithms and their manifolds; the contacts it still has are found again as
  // periodic pairs (they lose one step of warm starting). Those manifolds are freed, so they
  // leave solved_ first (reading them later was a use after free: a crash once Bullet's manifold
  // pool was full and they came from the heap, 4,000 spheres).
  std::set<const btPersistentManifold*> periodic;
  for (const auto& [key, pc] : periodic_) periodic.insert(pc.manifold.get());
  const std::set<const btCollisionObject*> moved(jumped.begin(), jumped.end());
  std::erase_if(solved_, [&](const btPersistentManifold* m) {
    return !periodic.count(m) && (moved.count(m->getBody0()) || moved.count(m->getBody1()));
  });
  for (btRigidBody* body : jumped)
    broadphase_->getOverlappingPairCache()->cleanProxyFromPairs(body->getBroadphaseHandle(), dispatcher_.get());
}

// Built from the SystemDef at the saved poses, the backend takes back the velocities. Its contact
// manifolds and their warm-start impulses are not part of the state (Bullet has no way to write
// them out): the first step after a restore finds the contacts again and solves them cold.
void BulletBackend::restoreState(const nlohmann::json& state) {
  if (!state.is_object() || !state.contains("grains"))
    throw std::invalid_argument("checkpoint: bullet state: expected an object with the grains' states");
  const std::vector<core::BodyState> saved = core::bodyStatesFromJson(state["grains"], grains_.size());
  for (std::size_t i = 0; i < grains_.size(); ++i) {
    grains_[i]->setLinearVelocity(toBt(saved[i].velocity));
    grains_[i]->setAngularVelocity(toBt(saved[i].angularVelocity));
  }
  readStates();
}

// One fixed step in Bullet's order (btDiscreteDynamicsWorld::stepSimulation and
// internalSingleStepSimulation): forces, collision at the current poses, the solve (gravity
// enters as the solver bodies' external impulse m g dt), integration. Bullet applies the warm
// start while it builds the rows, so WarmStart stays inside PrepareContacts.
void BulletBackend::step(double dt) {
  beginStep(dt);
  core::PhaseClock clock(profile_);
  applyForces(dt);
  clock.charge(Phase::Integrate);
  updatePairs();
  clock.charge(Phase::UpdatePairs);
  collide();
  clock.charge(Phase::Collide);
  prepareContacts();
  clock.charge(Phase::PrepareContacts);
  solveContacts();
  clock.charge(Phase::Solve);
  storeImpulses();
  clock.charge(Phase::StoreImpulses);
  integrate(dt);
  clock.charge(Phase::Integrate);
  readContacts(dt);  // before the wrap, which frees the broad-phase manifolds of grains that jump
  clock.charge(Phase::StoreImpulses);
  wrapIntoBox();
  clock.charge(Phase::Integrate);
  readStates();
  clock.charge(Phase::StoreImpulses);
}

// The step's settings: time step, and the early exit relative to the velocity gravity adds in
// one step (BulletSettings).
void BulletBackend::beginStep(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::invalid_argument(fmt::format("bullet: step dt must be a positive number (got {})", dt));
  dt_ = dt;
  profile_ = core::StepProfile{};
  btDispatcherInfo& dispatch = world_->getDispatchInfo();
  dispatch.m_timeStep = dt;
  dispatch.m_stepCount = 0;
  btContactSolverInfo& info = world_->getSolverInfo();
  info.m_timeStep = dt;
  const double exitVelocity = settings_.residualThreshold * system_.gravity.norm() * dt;
  info.m_leastSquaresResidualThreshold = exitVelocity * exitVelocity;
}

// Gravity as a force, and the interpolation transform (damping is zero; velocities untouched).
void BulletBackend::applyForces(double dt) {
  world_->applyGravity();
  world_->predict(dt);
}

// Broad-phase pairs at the current poses, then the pairs across periodic faces.
void BulletBackend::updatePairs() {
  world_->updateGrainAabbs(settings_.contactBreakingThreshold);
  world_->computeOverlappingPairs();
  findPeriodicPairs();
}

// Bullet's narrow phase over the broad-phase pairs, then over the periodic ones.
void BulletBackend::collide() {
  dispatcher_->dispatchAllCollisionPairs(broadphase_->getOverlappingPairCache(), world_->getDispatchInfo(),
                                         dispatcher_.get());
  collidePeriodicPairs();
}

void BulletBackend::prepareContacts() {
  gatherManifolds();
  solver_->prepare(grainObjects_.data(), static_cast<int>(grainObjects_.size()), solved_.data(),
                   static_cast<int>(solved_.size()), world_->getSolverInfo());
}

void BulletBackend::solveContacts() {
  solver_->iterate(grainObjects_.data(), static_cast<int>(grainObjects_.size()), solved_.data(),
                   static_cast<int>(solved_.size()), world_->getSolverInfo());
  profile_.iterations = solver_->iterationsUsed();
  profile_.residual = solver_->residual();
}

void BulletBackend::storeImpulses() {
  solver_->finish(grainObjects_.data(), static_cast<int>(grainObjects_.size()), world_->getSolverInfo());
}

// Positions and orientations from the new velocities; the forces are cleared for the next step.
void BulletBackend::integrate(double dt) {
  world_->integrate(dt);
  world_->clearForces();
}

void BulletBackend::readStates() {
  states_.resize(grains_.size());
  for (std::size_t i = 0; i < grains_.size(); ++i) {
    const btRigidBody& b = *grains_[i];
    const btTransform& t = b.getWorldTransform();
    const btQuaternion q = t.getRotation();
    core::BodyState& s = states_[i];
    s.position = fromBt(t.getOrigin());
    s.orientation = core::Quat(q.w(), q.x(), q.y(), q.z()).normalized();
    s.velocity = fromBt(b.getLinearVelocity());
    s.angularVelocity = fromBt(b.getAngularVelocity());
  }
}

void BulletBackend::readContacts(double dt) {
  contacts_.clear();
  // Shift of each solved periodic manifold (b's image = b + shift); interior ones have none.
  std::map<const btPersistentManifold*, Vec3> shifts;
  for (const auto& [key, pc] : periodic_) shifts[pc.manifold.get()] = pc.shift;
  int points = 0;
  for (const btPersistentManifold* m : solved_) {
    const int i0 = m->getBody0()->getUserIndex(), i1 = m->getBody1()->getUserIndex();
    auto it = shifts.find(m);
    const Vec3 shift = it == shifts.end() ? Vec3::Zero() : it->second;
    // a = grain body, b = the other; Bullet's normal points from body1 to body0.
    const bool swapped = i0 < 0 || (i1 >= 0 && i1 < i0);
    core::Contact c;
    c.a = swapped ? i1 : i0;
    c.b = swapped ? i0 : i1;
    Vec3 normalSum = Vec3::Zero();
    for (int k = 0; k < m->getNumContacts(); ++k) {
      const btManifoldPoint& cp = m->getContactPoint(k);
      const Vec3 nB = fromBt(cp.m_normalWorldOnB);
      normalSum += swapped ? nB : Vec3(-nB);
      // Midpoint of the two surface points in body0's periodic frame, then near grain a.
      Vec3 mid = 0.5 * (fromBt(cp.m_positionWorldOnA) + fromBt(cp.m_positionWorldOnB) + shift);
      if (swapped) mid -= shift;
      core::ContactPoint p;
      p.position = mid;
      p.normalForce = cp.m_appliedImpulse / dt;
      p.gap = cp.getDistance();
      // Friction impulse on body0 is lat1 dir1 + lat2 dir2 (the solver's m_contactNormal1).
      if (core::isWall(c.b) && cp.m_combinedFriction > 0.0) {
        Vec3 onBody0 = cp.m_appliedImpulseLateral1 * fromBt(cp.m_lateralFrictionDir1);
        if (settings_.frictionDirections == 2)
          onBody0 += cp.m_appliedImpulseLateral2 * fromBt(cp.m_lateralFrictionDir2);
        p.tangentForce = (swapped ? onBody0 : Vec3(-onBody0)) / dt;
      }
      c.points.push_back(p);
    }
    if (c.points.empty()) continue;
    c.normal = normalSum.normalized();
    c.type = c.points.size() == 1 ? core::ContactType::Simple
                                  : (c.points.size() == 2 ? core::ContactType::Double : core::ContactType::Triple);
    points += static_cast<int>(c.points.size());
    contacts_.push_back(std::move(c));
  }
  profile_.contactPoints = points;
}

std::vector<Vec3> BulletBackend::supportPoints(int grain, const std::vector<Vec3>& dirs) const {
  if (grain < 0 || grain >= static_cast<int>(grains_.size()))
    throw std::invalid_argument(fmt::format("inspect: no grain {}", grain));
  const auto* shape = static_cast<const btConvexShape*>(grains_[grain]->getCollisionShape());
  std::vector<Vec3> out;
  for (const Vec3& d : dirs) out.push_back(fromBt(shape->localGetSupportingVertex(toBt(d))));
  return out;
}

std::vector<double> BulletBackend::combinedFriction(int a, int b) const {
  std::vector<double> out;
  for (const btPersistentManifold* m : solved_) {
    const int i0 = m->getBody0()->getUserIndex(), i1 = m->getBody1()->getUserIndex();
    if ((i0 == a && i1 == b) || (i0 == b && i1 == a))
      for (int k = 0; k < m->getNumContacts(); ++k) out.push_back(m->getContactPoint(k).m_combinedFriction);
  }
  return out;
}

double BulletBackend::collisionMargin(int grain) const {
  if (grain < 0 || grain >= static_cast<int>(grains_.size()))
    throw std::invalid_argument(fmt::format("inspect: no grain {}", grain));
  return grains_[grain]->getCollisionShape()->getMargin();
}

const BulletBackend& asBullet(const core::ContactBackend& backend) {
  const auto* b = dynamic_cast<const BulletBackend*>(&backend);
  if (!b) throw std::invalid_argument(fmt::format("inspect: backend '{}' is not bullet", backend.name()));
  return *b;
}

}  // namespace

std::unique_ptr<core::ContactBackend> makeBulletBackend(const core::SystemDef& system, const nlohmann::json& options) {
  return std::make_unique<BulletBackend>(system, bulletSettingsFromJson(options));
}

namespace inspect {

std::vector<core::Vec3> supportPoints(const core::ContactBackend& backend, int grain,
                                      const std::vector<core::Vec3>& bodyDirections) {
  return asBullet(backend).supportPoints(grain, bodyDirections);
}

std::vector<double> combinedFriction(const core::ContactBackend& backend, int a, int b) {
  return asBullet(backend).combinedFriction(a, b);
}

double collisionMargin(const core::ContactBackend& backend, int grain) {
  return asBullet(backend).collisionMargin(grain);
}

}  // namespace inspect

}  // namespace confpack::bullet
