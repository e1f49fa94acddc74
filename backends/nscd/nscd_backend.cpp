#include "backends/nscd/nscd_backend.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "backends/nscd/broad_phase.hpp"
#include "backends/nscd/contact_cache.hpp"
#include "backends/nscd/contact_solver.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_settings.hpp"

namespace confpack::nscd {

using core::Mat3;
using core::Phase;
using core::Quat;
using core::Vec3;

namespace {

/// MPRGP's relative residual for a finisher step after one the trust radius cut (quasiStaticStep).
constexpr double kRoughTolerance = 1e-6;

/// Exact rotation of q by the angle |w| h about w (then renormalised against round-off).
Quat rotate(const Quat& q, const Vec3& w, double h) {
  const double angle = w.norm() * h;
  if (angle == 0.0) return q;
  Quat r(Eigen::AngleAxisd(angle, w.normalized()) * q);
  r.normalize();
  return r;
}

/// What a step reads of the system besides the grains.
struct World {
  core::BoxDef box;
  core::WallMaterial walls;
  Vec3 gravity;
};

/// Cold data of the grains: mass properties in the body frame, reach and spin lever.
struct GrainProperties {
  std::vector<double> invMass;
  std::vector<Mat3> inertiaBody, invInertiaBody;
  std::vector<double> reach;
  std::vector<double> spinLever;  // Grain::spinLever of each grain
  bool pinacoids = false;         // some grain is not a sphere
};

/// State q_i (wrapped) and the predicted configuration q_m.
struct Poses {
  std::vector<Vec3> position, positionMid;
  std::vector<Quat> orientation, orientationMid;
};

/// The step's working lists, reused from step to step: candidate pairs, contact geometry and the
/// impulses exported for the contact cache.
struct StepBuffers {
  std::vector<CandidatePair> pairs;
  std::vector<ContactGeometry> geometry;
  std::vector<CachedContact> cacheBuffer;
};

/// The finisher's state (NscdBackend::quasiStaticStep): its contact law and solver settings, the
/// per-grain metric weights and each grain's last move, whether its last step was clipped, and
/// whether the "auto" finisher fell back to the interior point. Verbs: useSolver,
/// fallBackToInteriorPoint, updateMetricWeight, report.
struct FinisherState {
  NscdSettings settings;
  bool lastStepClipped = false;
  bool fellBack = false;  // fallBackToInteriorPoint() switched the solver
  std::vector<double> metricWeight;
  std::vector<BodyVelocity> lastMove;

  // `kind` solves the finisher's steps: with the run's max_iterations when it is also the steps'
  // solver, else with its own default cap; with the steps' tolerance, unless they run NLGS, whose
  // tolerance measures something else.
  void useSolver(SolverKind kind, const NscdSettings& run) {
    const NscdSettings own = kind == run.solver ? run : defaultsFor(kind);
    settings.solver = kind;
    settings.maxIterations = own.maxIterations;
    if (run.solver == SolverKind::Nlgs) settings.tolerance = own.tolerance;
  }

  // "auto" finisher of a pinacoid pile: MPRGP until a step's solve ends at its iteration cap, then
  // the interior point from the next step to the end of the run. A capped step is inexact, and
  // inexact steps reverse, weigh the grains down and never settle (on a 1,064-pinacoid pile every
  // step at the cap of 5,000, residual median 9e-7, metric weights up to 5.2e5); the interior
  // point's iterations hardly depend on conditioning (29 to 61 a step there) and it brings that
  // pile to rest (docs/performance.md, "The finisher's solves at their cap"). Not against
  // frictional walls: there both solvers reach their caps in the block iteration around the
  // Coulomb law, and the interior point's steps are the worse (docs/limitations.md).
  void fallBackToInteriorPoint(const NscdSettings& run, const core::WallMaterial& walls) {
    if (run.finisherSolver != FinisherSolverKind::Auto || settings.solver != SolverKind::Mprgp) return;
    if (walls.friction > 0.0) return;
    useSolver(SolverKind::Ipm, run);
    fellBack = true;
  }

  // Per-grain metric weights of the finisher (docs/model.md). The finisher's fixed point dq = 0 is
  // static equilibrium whatever the metric, so the weights change the path, not the packing.
  // After each step, grain i's weight (`now` its move, d its surface move, `lever` its spin lever)
  // is multiplied by
  // - d / trustRadius when its unscaled move d exceeded the trust radius, so that its next free
  //   move is about the trust radius and it does not scale the whole next step down again;
  // - 4 when its move reverses its last one without shrinking to less than half of it (a move
  //   above 1e-4 of the trust radius): with h = 1 t0 a pinacoid rocking between an edge and a face
  //   overshoots, a 2-cycle that grew by 6 % a step and never settled in 3,000 steps; a heavier
  //   grain takes a shorter step of its own. A reversal that halves the move is an approach that
  //   converges: weighed too, grains of a flat, sharp pinacoid pile grew heavy enough to move
  //   1e-5 d a step for 3,000 steps, where the same pile with fresh weights was at rest in 14;
  // - 1/2 when it moved less than a quarter of the trust radius, down to a weight of 1.
  void updateMetricWeight(int i, const BodyVelocity& now, double lever, double d, double trustRadius) {
    BodyVelocity& last = lastMove[i];
    const double r2 = lever * lever;
    const double lastSize2 = last.v.squaredNorm() + r2 * last.w.squaredNorm();
    const double nowSize2 = now.v.squaredNorm() + r2 * now.w.squaredNorm();
    const bool reversed =
        last.v.dot(now.v) + r2 * last.w.dot(now.w) < 0.0 && d > 1e-4 * trustRadius && nowSize2 >= 0.25 * lastSize2;
    double factor = reversed ? 4.0 : 1.0;
    if (d > trustRadius)
      factor *= d / trustRadius;
    else if (d < 0.25 * trustRadius)
      factor *= 0.5;
    metricWeight[i] = std::max(1.0, metricWeight[i] * factor);
    last = now;
  }

  nlohmann::json report() const {
    // The solver's name as the settings table writes it.
    return {{"solver", nlohmann::json(settings).at("solver")}, {"switched_from_mprgp", fellBack}};
  }
};

/// Damping (settings "damping" c, "damping_speed" v_d): the velocity and angular velocity of
/// every grain that carried a contact impulse in the last step and moves slower than v_d are
/// multiplied by exp(-c dt), before the free velocity. Verbs: damp, and startRecording and
/// markLoaded, with which storeImpulses() records the loaded grains.
// The same factor for every loaded grain, so the relative velocity at a contact between two of
// them scales alike and the contact problem keeps its structure. Rules that damp only unbalanced
// motion cost more (a 188-pinacoid pile): Cundall's local damping (each velocity component cut
// by alpha |its change|) 1.5 to 7 times the MPRGP iterations per step, damping only decelerating
// grains (v . dv < 0) 1.2 to 2 times, and it settles more slowly.
struct Damping {
  // Grains that carried a contact impulse in the last step (only with settings "damping" > 0).
  std::vector<char> loaded;

  void damp(std::vector<BodyVelocity>& velocity, int n, double factor, double speed) const {
    const double speed2 = speed * speed;
    for (int i = 0; i < n && i < static_cast<int>(loaded.size()); ++i) {
      if (!loaded[i] || velocity[i].v.squaredNorm() > speed2) continue;
      velocity[i].v *= factor;
      velocity[i].w *= factor;
    }
  }
  void startRecording(int n) { loaded.assign(n, 0); }
  void markLoaded(int a, int b) {
    loaded[a] = 1;
    if (b >= 0) loaded[b] = 1;
  }
};

// Moreau-Jean theta time stepping (docs/model.md, "nscd: Moreau-Jean contact dynamics"):
//   v_free  = v_i + dt g                      (gravity is the only external force)
//   q_m     = q_i + dt (1 - theta) v_i        (contacts are detected here)
//   v_{i+1} = v_free + M^-1 H r               (r from the contact solver: MPRGP or NLGS)
//   q_{i+1} = q_m + dt theta v_{i+1}
// Rotations use the exact rotation of angle |w| h for each partial step h. Without torques the
// world-frame angular momentum is conserved, so the free angular velocity is
// w_free = I_m^-1 (I_i w_i) with the inertia of q_m (exact for spheres, whose w is unchanged; for
// pinacoids the explicit first-order treatment of the gyroscopic term).
// With theta = 1/2 and a constant force the scheme integrates positions exactly:
// q_{i+1} = q_i + dt v_i - dt^2 g / 2. For theta != 1/2 the error after time t is (theta - 1/2) g t dt.
class NscdBackend final : public core::ContactBackend {
 public:
  NscdBackend(const core::SystemDef& system, const NscdSettings& settings)
      : world_{system.box, system.walls, system.gravity},
        settings_(settings),
        n_(static_cast<int>(system.grains.size())),
        narrow_(system.box, system.grains, settings.alertDistance,
                settings.contactDetection == ContactDetection::CommonPlane ? settings.commonPlaneBand : 0.0),
        threads_(system.threads),
        broad_(system.box, n_ > 0 ? narrow_.maxReach() : 1.0, system.threads) {
    world_.box.validate();
    world_.walls.validate();
    if (!world_.gravity.allFinite()) throw std::invalid_argument("nscd: gravity must be finite");
    if (!(system.density > 0.0) || !std::isfinite(system.density))
      throw std::invalid_argument("nscd: density must be a positive number");
    grains_.inertiaBody.reserve(n_);
    grains_.invInertiaBody.reserve(n_);
    inverse_.resize(n_ + 1);  // the last body is the static world (walls)
    velocity_.resize(n_ + 1);
    for (const core::Grain& g : system.grains) {
      if (!g.position.allFinite()) throw std::invalid_argument("nscd: grain positions must be finite");
      const double m = system.density * g.volume();
      const Mat3 inertia = g.bodyInertia(system.density);
      grains_.invMass.push_back(1.0 / m);
      grains_.inertiaBody.push_back(inertia);
      grains_.invInertiaBody.push_back(inertia.inverse());
      poses_.position.push_back(world_.box.wrap(g.position));
      poses_.orientation.push_back(g.orientation.normalized());
      grains_.reach.push_back(narrow_.reach(static_cast<int>(grains_.reach.size())));
      grains_.spinLever.push_back(g.spinLever());
    }
    // The finisher's contact problem (quasiStaticStep): implicit Euler (theta = 1), so that the
    // displacement h v is the one the linearised gaps constrain, and overlaps removed whole (held,
    // under contact_law "velocity").
    stepSolve_ = settings_;
    finisher_.settings = settings_;
    SolverKind finisher = settings_.finisherSolver == FinisherSolverKind::Mprgp ? SolverKind::Mprgp : SolverKind::Ipm;
    for (const core::Grain& g : system.grains)
      grains_.pinacoids = grains_.pinacoids || g.shape != core::ShapeKind::Sphere;
    if (settings_.finisherSolver == FinisherSolverKind::Auto && grains_.pinacoids) finisher = SolverKind::Mprgp;
    finisher_.useSolver(finisher, settings_);
    finisher_.settings.theta = 1.0;
    finisher_.settings.gapCorrection = 1.0;
    finisher_.settings.maxCorrectionVelocity = std::numeric_limits<double>::infinity();
    finisher_.metricWeight.assign(n_, 1.0);
    finisher_.lastMove.assign(n_, BodyVelocity{});
    poses_.positionMid = poses_.position;
    poses_.orientationMid = poses_.orientation;
    states_.resize(n_);
    writeStates();
  }

  std::string_view name() const override { return "nscd"; }
  const std::vector<core::BodyState>& states() const override { return states_; }
  const std::vector<core::Contact>& contacts() const override { return contacts_; }
  const core::StepProfile& profile() const override { return profile_; }
  nlohmann::json settings() const override { return settings_; }

  void step(double dt) override {
    if (!(dt > 0.0) || !std::isfinite(dt)) throw std::invalid_argument("nscd: time step dt must be positive");
    profile_ = core::StepProfile{};
    core::PhaseClock clock(profile_);
    if (settings_.damping > 0.0)
      damping_.damp(velocity_, n_, std::exp(-settings_.damping * dt), settings_.dampingSpeed);
    predict(dt);
    clock.charge(Phase::Integrate);
    solveContacts(dt, settings_, stepSolve_, clock);
    correct(dt, settings_.theta);
    clock.charge(Phase::Integrate);
    storeImpulses(dt, settings_.theta);
    clock.charge(Phase::StoreImpulses);
  }

  bool hasQuasiStaticStep() const override { return true; }

  void startQuasiStaticFall() override {
    double tolerance = settings_.fallTolerance;
    if (tolerance == 0.0) tolerance = grains_.pinacoids ? kPinacoidFallTolerance : settings_.tolerance;
    stepSolve_.tolerance = tolerance;
  }

  // Everything a step reads besides the SystemDef: poses and velocities (states_ is a copy of
  // poses_ and velocity_), the warm-start impulses, the damping's loaded grains
  // and the finisher's metric state. The narrow phase's and the broad phase's data are rebuilt
  // by every step.
  nlohmann::json saveState() const override {
    nlohmann::json lastMove = nlohmann::json::array();
    for (const BodyVelocity& m : finisher_.lastMove)
      lastMove.push_back({m.v.x(), m.v.y(), m.v.z(), m.w.x(), m.w.y(), m.w.z()});
    const SwitchState switchState = solver_.switchState();
    return {{"grains", core::bodyStatesToJson(states_)},
            {"cache", cache_.toJson()},
            {"loaded", damping_.loaded},
            {"metric_weights", finisher_.metricWeight},
            {"last_moves", std::move(lastMove)},
            {"last_finisher_step_clipped", finisher_.lastStepClipped},
            {"finisher_fell_back", finisher_.fellBack},
            {"preconditioner_switch", {{"on_cholesky", switchState.onCholesky}, {"solves", switchState.solves}}}};
  }

  void restoreState(const nlohmann::json& state) override {
    const auto bad = [](const char* what) {
      return std::invalid_argument(fmt::format("checkpoint: nscd state: {}", what));
    };
    if (!state.is_object()) throw bad("not an object");
    const std::vector<core::BodyState> grains = core::bodyStatesFromJson(state.value("grains", nlohmann::json()), n_);
    const nlohmann::json& weights = state.value("metric_weights", nlohmann::json());
    const nlohmann::json& moves = state.value("last_moves", nlohmann::json());
    const nlohmann::json& loaded = state.value("loaded", nlohmann::json());
    if (!weights.is_array() || weights.size() != static_cast<std::size_t>(n_)) throw bad("metric_weights");
    if (!moves.is_array() || moves.size() != static_cast<std::size_t>(n_)) throw bad("last_moves");
    if (!loaded.is_array() || (!loaded.empty() && loaded.size() != static_cast<std::size_t>(n_))) throw bad("loaded");
    if (!state.value("last_finisher_step_clipped", nlohmann::json()).is_boolean())
      throw bad("last_finisher_step_clipped");
    // Absent from the checkpoints of earlier versions, which had no fallback.
    const nlohmann::json& fellBack = state.value("finisher_fell_back", nlohmann::json(false));
    if (!fellBack.is_boolean()) throw bad("finisher_fell_back");
    // Absent from the checkpoints of earlier versions, which had no "switching" preconditioner.
    const nlohmann::json& switching = state.value("preconditioner_switch", nlohmann::json::object());
    if (!switching.is_object()) throw bad("preconditioner_switch");
    const nlohmann::json& onCholesky = switching.value("on_cholesky", nlohmann::json(false));
    const nlohmann::json& solves = switching.value("solves", nlohmann::json(0));
    if (!onCholesky.is_boolean() || !solves.is_number_integer() || solves.get<long>() < 0 ||
        solves.get<long>() > std::numeric_limits<int>::max())
      throw bad("preconditioner_switch");
    cache_.fromJson(state.value("cache", nlohmann::json()), n_);
    // The poses again, although the SystemDef had them: the constructor wraps and normalises them,
    // which may change their last bits.
    for (int i = 0; i < n_; ++i) {
      poses_.position[i] = grains[i].position;
      poses_.orientation[i] = grains[i].orientation;
      velocity_[i] = {grains[i].velocity, grains[i].angularVelocity};
      if (!weights[i].is_number() || !(weights[i].get<double>() >= 1.0)) throw bad("metric_weights");
      finisher_.metricWeight[i] = weights[i].get<double>();
      const nlohmann::json& m = moves[i];
      if (!m.is_array() || m.size() != 6) throw bad("last_moves");
      double x[6];
      for (int k = 0; k < 6; ++k) {
        if (!m[k].is_number()) throw bad("last_moves");
        x[k] = m[k].get<double>();
      }
      finisher_.lastMove[i] = {Vec3(x[0], x[1], x[2]), Vec3(x[3], x[4], x[5])};
    }
    damping_.loaded = loaded.get<std::vector<char>>();
    finisher_.lastStepClipped = state["last_finisher_step_clipped"].get<bool>();
    if (fellBack.get<bool>()) finisher_.fallBackToInteriorPoint(settings_, world_.walls);
    solver_.setSwitchState({onCholesky.get<bool>(), solves.get<int>()});
    poses_.positionMid = poses_.position;
    poses_.orientationMid = poses_.orientation;
    writeStates();
  }

  bool exactRestore() const override { return true; }

  // The Moreau-Jean step from rest with theta = 1: v_free = h g / w_i, the contact law with the
  // gaps closed exactly (finisher_.settings), then dq = h v_{i+1}, which is the minimiser of
  // 1/2 dq.W M dq / h^2 - F_ext.dq under the linearised non-penetration constraints (the contact
  // problem's quadratic program written for dq = h v), W = diag(w_i) the per-grain metric weights
  // of FinisherState::updateMetricWeight(). Side-wall friction stays in the problem: the Coulomb law on the
  // tangential displacement of the step (docs/model.md).
  // After a step that the trust radius cut, the next is solved to kRoughTolerance only: such a
  // step is a descent direction, not an equilibrium, and MPRGP's iterations near jamming grow with
  // the accuracy asked; an overlap its looser solve leaves is removed whole by the next step.
  core::QuasiStaticMove quasiStaticStep(double h, double trustRadius) override {
    if (!(h > 0.0) || !std::isfinite(h)) throw std::invalid_argument("nscd: quasi-static step h must be positive");
    if (!(trustRadius > 0.0)) throw std::invalid_argument("nscd: quasi-static trust radius must be positive");
    profile_ = core::StepProfile{};
    core::PhaseClock clock(profile_);
    for (int i = 0; i < n_; ++i) velocity_[i] = BodyVelocity{};
    predict(h);                     // from rest: q_m = q_i, v_free = h g
    for (int i = 0; i < n_; ++i) {  // grain i's mass and inertia times w_i
      inverse_[i].invMass /= finisher_.metricWeight[i];
      inverse_[i].invInertia /= finisher_.metricWeight[i];
      velocity_[i].v /= finisher_.metricWeight[i];
    }
    clock.charge(Phase::Integrate);
    NscdSettings solve = finisher_.settings;
    if (finisher_.lastStepClipped) solve.tolerance = std::max(solve.tolerance, kRoughTolerance);
    solveContacts(h, finisher_.settings, solve, clock);
    if (profile_.iterations >= solve.maxIterations) finisher_.fallBackToInteriorPoint(settings_, world_.walls);
    // The trust radius caps the largest motion of a grain's surface in a step: when some grain
    // would move further, the whole step is scaled down to it. A scaled step stays inside the
    // linearised constraints (they are convex), so it leaves only the linearisation's overlaps.
    // Capping each grain alone would leave a capped grain's neighbours their whole move: overlaps
    // of about the trust radius at the next step (median 8.7e-3 d against 1e-3 d on a 1,064-pinacoid
    // pile), moves that reverse, metric weights without bound and a pile that never settles; scaled
    // whole, that pile is at rest in 479 steps (docs/performance.md, "The medium scale: how its
    // piles reach rest").
    // The grain that set the scale gets heavier (FinisherState::updateMetricWeight), so that one grain still
    // rearranging does not hold the whole pile to its pace for long.
    double largest = 0.0;
    for (int i = 0; i < n_; ++i) largest = std::max(largest, surfaceMove(i, h));
    const double scale = largest > trustRadius ? trustRadius / largest : 1.0;
    core::QuasiStaticMove move;
    move.clipped = scale < 1.0;
    move.maxDisplacement = largest * scale;
    for (int i = 0; i < n_; ++i) {
      const double d = surfaceMove(i, h);
      velocity_[i].v *= scale;
      velocity_[i].w *= scale;
      finisher_.updateMetricWeight(i, velocity_[i], grains_.spinLever[i], d, trustRadius);
    }
    finisher_.lastStepClipped = move.clipped;
    correct(h, 1.0);
    clock.charge(Phase::Integrate);
    storeImpulses(h, 1.0);
    clock.charge(Phase::StoreImpulses);
    return move;
  }

  nlohmann::json finisherReport() const override { return finisher_.report(); }

  // The contact problem of a step from q_m and the free velocities: pairs, contact points, rows
  // (with `law`'s contact law), warm start, then the solve to `solve`'s tolerance, each phase
  // timed into profile_.
  void solveContacts(double dt, const NscdSettings& law, const NscdSettings& solve, core::PhaseClock& clock) {
    broad_.findPairs(poses_.positionMid, grains_.reach, buffers_.pairs);
    clock.charge(Phase::UpdatePairs);
    collide();
    clock.charge(Phase::Collide);
    solver_.prepare(buffers_.geometry, poses_.positionMid, inverse_, world_.box, world_.walls, dt, law);
    clock.charge(Phase::PrepareContacts);
    solver_.warmStart(cache_, buffers_.geometry, dt, velocity_);
    clock.charge(Phase::WarmStart);
    profile_.iterations = solver_.solve(velocity_, solve, threads_);
    profile_.residual = solver_.residual();
    profile_.contactPoints = solver_.rowCount();
    clock.charge(Phase::Solve);
  }

  // How far grain i's surface moves in a step of length h at its velocity: |v| h + |w| lever h
  // (Grain::spinLever, 0 for a sphere: a sphere rolling on a frictional wall must not cut the step
  // or keep the pile from settling).
  double surfaceMove(int i, double h) const {
    return h * (velocity_[i].v.norm() + velocity_[i].w.norm() * grains_.spinLever[i]);
  }

  // q_m, the world inverse inertia there, and the free velocities. One thread: the loop is ~8%
  // of a step, and any OpenMP construct in this class (even a region never entered) makes the
  // compiled single-thread loop ~10-20% slower, for no measurable gain on 2 threads.
  void predict(double dt) {
    const double h = dt * (1.0 - settings_.theta);
    for (int i = 0; i < n_; ++i) {
      BodyVelocity& v = velocity_[i];
      const Mat3 r0 = poses_.orientation[i].toRotationMatrix();
      const Vec3 angularMomentum = r0 * (grains_.inertiaBody[i] * (r0.transpose() * v.w));
      poses_.positionMid[i] = poses_.position[i] + h * v.v;
      poses_.orientationMid[i] = rotate(poses_.orientation[i], v.w, h);
      const Mat3 rm = poses_.orientationMid[i].toRotationMatrix();
      inverse_[i].invMass = grains_.invMass[i];
      inverse_[i].invInertia = rm * grains_.invInertiaBody[i] * rm.transpose();
      v.w = inverse_[i].invInertia * angularMomentum;
      v.v += dt * world_.gravity;
    }
  }

  // Pair contacts in pair order, then wall contacts in grain order, whatever the thread count.
  void collide() {
    narrow_.collideAll(buffers_.pairs, poses_.positionMid, poses_.orientationMid, buffers_.geometry, threads_);
  }

  // q_{i+1} = q_m + dt theta v_{i+1}, wrapped into the box.
  void correct(double dt, double theta) {
    const double h = dt * theta;
    for (int i = 0; i < n_; ++i) {
      const BodyVelocity& v = velocity_[i];
      poses_.position[i] = world_.box.wrap(poses_.positionMid[i] + h * v.v);
      poses_.orientation[i] = rotate(poses_.orientationMid[i], v.w, h);
    }
  }

  void storeImpulses(double dt, double theta) {
    solver_.exportImpulses(buffers_.geometry, buffers_.cacheBuffer);
    cache_.replace(buffers_.cacheBuffer, dt);
    // Contact list: every contact that carries force or is closed. Objects (and their point
    // vectors) are reused from step to step, so the list costs no allocation in steady state.
    // The same pass records which grains carried an impulse, for Damping::damp() in the next step.
    std::size_t count = 0;
    const bool damping = settings_.damping > 0.0;
    if (damping) damping_.startRecording(n_);
    for (std::size_t c = 0; c < buffers_.geometry.size(); ++c) {
      const ContactGeometry& g = buffers_.geometry[c];
      bool loaded = false, closed = false;
      for (int p = 0; p < g.pointCount; ++p) {
        loaded |= solver_.normalImpulse(static_cast<int>(c), p) > 0.0;
        closed |= g.gaps[p] <= 0.0;
      }
      if (damping && loaded) damping_.markLoaded(g.a, g.b);
      if (!loaded && !closed) continue;
      if (contacts_.size() <= count) contacts_.emplace_back();
      core::Contact& out = contacts_[count++];
      out.a = g.a;
      out.b = g.b;
      out.type = g.type;
      out.normal = g.normal;
      out.points.resize(g.pointCount);
      // Points were computed at q_m near a; move them with a's wrap so they stay near the
      // reported position of a (core/contact.hpp).
      const Vec3 unwrapped = poses_.positionMid[g.a] + dt * theta * velocity_[g.a].v;
      const Vec3 shift = poses_.position[g.a] - unwrapped;
      for (int p = 0; p < g.pointCount; ++p) {
        core::ContactPoint& cp = out.points[p];
        cp.position = g.points[p] + shift;
        cp.normalForce = solver_.normalImpulse(static_cast<int>(c), p) / dt;
        cp.tangentForce = solver_.tangentImpulse(static_cast<int>(c), p) / dt;
        cp.gap = g.gaps[p];
      }
    }
    contacts_.resize(count);
    writeStates();
  }

  void writeStates() {
    for (int i = 0; i < n_; ++i) {
      states_[i].position = poses_.position[i];
      states_[i].orientation = poses_.orientation[i];
      states_[i].velocity = velocity_[i].v;
      states_[i].angularVelocity = velocity_[i].w;
    }
  }

  World world_;
  NscdSettings settings_;
  int n_ = 0;
  GrainProperties grains_;
  NscdSettings stepSolve_;  // settings_, or the fall's looser tolerance (startQuasiStaticFall)
  FinisherState finisher_;
  Poses poses_;
  // Hot solver state: velocities and inverse masses, one extra static body for the walls.
  std::vector<BodyVelocity> velocity_;
  std::vector<BodyInverseMass> inverse_;
  Damping damping_;
  NarrowPhase narrow_;
  // Most OpenMP threads of a phase (the run's `threads`, SystemDef::threads): the broad and narrow
  // phases and MPRGP's passes each time their team against one thread and keep the faster
  // (thread_choice.hpp); results are the same bits for any value; NLGS stays sequential.
  int threads_ = 1;
  BroadPhase broad_;
  StepBuffers buffers_;
  ContactSolver solver_;
  ContactCache cache_;
  std::vector<core::BodyState> states_;
  std::vector<core::Contact> contacts_;
  core::StepProfile profile_;
};

}  // namespace

std::unique_ptr<core::ContactBackend> makeNscdBackend(const core::SystemDef& system, const nlohmann::json& options) {
  NscdSettings settings = settingsFromJson(options);
  if (system.threads < 1) throw std::invalid_argument("nscd: threads must be >= 1");
  return std::make_unique<NscdBackend>(system, settings);
}

}  // namespace confpack::nscd
