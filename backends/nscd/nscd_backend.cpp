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
      : box_(system.box),
        walls_(system.walls),
        gravity_(system.gravity),
        settings_(settings),
        n_(static_cast<int>(system.grains.size())),
        narrow_(system.box, system.grains, settings.alertDistance,
                settings.contactDetection == ContactDetection::CommonPlane ? settings.commonPlaneBand : 0.0),
        threads_(system.threads),
        broad_(system.box, n_ > 0 ? narrow_.maxReach() : 1.0, system.threads) {
    box_.validate();
    walls_.validate();
    if (!gravity_.allFinite()) throw std::invalid_argument("nscd: gravity must be finite");
    if (!(system.density > 0.0) || !std::isfinite(system.density))
      throw std::invalid_argument("nscd: density must be a positive number");
    inertiaBody_.reserve(n_);
    invInertiaBody_.reserve(n_);
    inverse_.resize(n_ + 1);  // the last body is the static world (walls)
    velocity_.resize(n_ + 1);
    for (const core::Grain& g : system.grains) {
      if (!g.position.allFinite()) throw std::invalid_argument("nscd: grain positions must be finite");
      const double m = system.density * g.volume();
      const Mat3 inertia = g.bodyInertia(system.density);
      invMass_.push_back(1.0 / m);
      inertiaBody_.push_back(inertia);
      invInertiaBody_.push_back(inertia.inverse());
      position_.push_back(box_.wrap(g.position));
      orientation_.push_back(g.orientation.normalized());
      reach_.push_back(narrow_.reach(static_cast<int>(reach_.size())));
      spinLever_.push_back(g.spinLever());
    }
    // The finisher's contact problem (quasiStaticStep): implicit Euler (theta = 1), so that the
    // displacement h v is the one the linearised gaps constrain, and overlaps removed whole (held,
    // under contact_law "velocity").
    stepSolve_ = settings_;
    finisherSettings_ = settings_;
    SolverKind finisher = settings_.finisherSolver == FinisherSolverKind::Mprgp ? SolverKind::Mprgp : SolverKind::Ipm;
    for (const core::Grain& g : system.grains) pinacoids_ = pinacoids_ || g.shape != core::ShapeKind::Sphere;
    if (settings_.finisherSolver == FinisherSolverKind::Auto && pinacoids_) finisher = SolverKind::Mprgp;
    useFinisherSolver(finisher);
    finisherSettings_.theta = 1.0;
    finisherSettings_.gapCorrection = 1.0;
    finisherSettings_.maxCorrectionVelocity = std::numeric_limits<double>::infinity();
    metricWeight_.assign(n_, 1.0);
    lastMove_.assign(n_, BodyVelocity{});
    positionMid_ = position_;
    orientationMid_ = orientation_;
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
    if (settings_.damping > 0.0) damp(std::exp(-settings_.damping * dt));
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
    if (tolerance == 0.0) tolerance = pinacoids_ ? kPinacoidFallTolerance : settings_.tolerance;
    stepSolve_.tolerance = tolerance;
  }

  // Everything a step reads besides the SystemDef: poses and velocities (states_ is a copy of
  // position_, orientation_ and velocity_), the warm-start impulses, the damping's loaded grains
  // and the finisher's metric state. The narrow phase's and the broad phase's data are rebuilt
  // by every step.
  nlohmann::json saveState() const override {
    nlohmann::json lastMove = nlohmann::json::array();
    for (const BodyVelocity& m : lastMove_) lastMove.push_back({m.v.x(), m.v.y(), m.v.z(), m.w.x(), m.w.y(), m.w.z()});
    return {{"grains", core::bodyStatesToJson(states_)},
            {"cache", cache_.toJson()},
            {"loaded", loaded_},
            {"metric_weights", metricWeight_},
            {"last_moves", std::move(lastMove)},
            {"last_finisher_step_clipped", lastFinisherStepClipped_},
            {"finisher_fell_back", finisherFellBack_}};
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
    cache_.fromJson(state.value("cache", nlohmann::json()), n_);
    // The poses again, although the SystemDef had them: the constructor wraps and normalises them,
    // which may change their last bits.
    for (int i = 0; i < n_; ++i) {
      position_[i] = grains[i].position;
      orientation_[i] = grains[i].orientation;
      velocity_[i] = {grains[i].velocity, grains[i].angularVelocity};
      if (!weights[i].is_number() || !(weights[i].get<double>() >= 1.0)) throw bad("metric_weights");
      metricWeight_[i] = weights[i].get<double>();
      const nlohmann::json& m = moves[i];
      if (!m.is_array() || m.size() != 6) throw bad("last_moves");
      double x[6];
      for (int k = 0; k < 6; ++k) {
        if (!m[k].is_number()) throw bad("last_moves");
        x[k] = m[k].get<double>();
      }
      lastMove_[i] = {Vec3(x[0], x[1], x[2]), Vec3(x[3], x[4], x[5])};
    }
    loaded_ = loaded.get<std::vector<char>>();
    lastFinisherStepClipped_ = state["last_finisher_step_clipped"].get<bool>();
    if (fellBack.get<bool>()) fallBackToInteriorPoint();
    positionMid_ = position_;
    orientationMid_ = orientation_;
    writeStates();
  }

  bool exactRestore() const override { return true; }

  // The Moreau-Jean step from rest with theta = 1: v_free = h g / w_i, the contact law with the
  // gaps closed exactly (finisherSettings_), then dq = h v_{i+1}, which is the minimiser of
  // 1/2 dq.W M dq / h^2 - F_ext.dq under the linearised non-penetration constraints (the contact
  // problem's quadratic program written for dq = h v), W = diag(w_i) the per-grain metric weights
  // of updateMetricWeight(). Side-wall friction stays in the problem: the Coulomb law on the
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
    predict(h);  // from rest: q_m = q_i, v_free = h g
    for (int i = 0; i < n_; ++i) {  // grain i's mass and inertia times w_i
      inverse_[i].invMass /= metricWeight_[i];
      inverse_[i].invInertia /= metricWeight_[i];
      velocity_[i].v /= metricWeight_[i];
    }
    clock.charge(Phase::Integrate);
    NscdSettings solve = finisherSettings_;
    if (lastFinisherStepClipped_) solve.tolerance = std::max(solve.tolerance, kRoughTolerance);
    solveContacts(h, finisherSettings_, solve, clock);
    if (profile_.iterations >= solve.maxIterations) fallBackToInteriorPoint();
    // The trust radius caps the largest motion of a grain's surface in a step: when some grain
    // would move further, the whole step is scaled down to it. A scaled step stays inside the
    // linearised constraints (they are convex), so it leaves only the linearisation's overlaps.
    // Capping each grain alone would leave a capped grain's neighbours their whole move: overlaps
    // of about the trust radius at the next step (median 8.7e-3 d against 1e-3 d on a 1,064-pinacoid
    // pile), moves that reverse, metric weights without bound and a pile that never settles; scaled
    // whole, that pile is at rest in 479 steps (docs/performance.md, "The medium scale").
    // The grain that set the scale gets heavier (updateMetricWeight), so that one grain still
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
      updateMetricWeight(i, d, trustRadius);
    }
    lastFinisherStepClipped_ = move.clipped;
    correct(h, 1.0);
    clock.charge(Phase::Integrate);
    storeImpulses(h, 1.0);
    clock.charge(Phase::StoreImpulses);
    return move;
  }

  // "auto" finisher of a pinacoid pile: MPRGP until a step's solve ends at its iteration cap, then
  // the interior point from the next step to the end of the run. A capped step is inexact, and
  // inexact steps reverse, weigh the grains down and never settle (on a 1,064-pinacoid pile every
  // step at the cap of 5,000, residual median 9e-7, metric weights up to 5.2e5); the interior
  // point's iterations hardly depend on conditioning (29 to 61 a step there) and it brings that
  // pile to rest (docs/performance.md, "The finisher's solves at their cap"). Not against
  // frictional walls: there both solvers reach their caps in the block iteration around the
  // Coulomb law, and the interior point's steps are the worse (docs/limitations.md).
  void fallBackToInteriorPoint() {
    if (settings_.finisherSolver != FinisherSolverKind::Auto || finisherSettings_.solver != SolverKind::Mprgp) return;
    if (walls_.friction > 0.0) return;
    useFinisherSolver(SolverKind::Ipm);
    finisherFellBack_ = true;
  }

  // `kind` solves the finisher's steps: with the run's max_iterations when it is also the steps'
  // solver, else with its own default cap; with the steps' tolerance, unless they run NLGS, whose
  // tolerance measures something else.
  void useFinisherSolver(SolverKind kind) {
    const NscdSettings own = kind == settings_.solver ? settings_ : defaultsFor(kind);
    finisherSettings_.solver = kind;
    finisherSettings_.maxIterations = own.maxIterations;
    if (settings_.solver == SolverKind::Nlgs) finisherSettings_.tolerance = own.tolerance;
  }

  nlohmann::json finisherReport() const override {
    // The solver's name as the settings table writes it.
    return {{"solver", nlohmann::json(finisherSettings_).at("solver")}, {"switched_from_mprgp", finisherFellBack_}};
  }

  // The contact problem of a step from q_m and the free velocities: pairs, contact points, rows
  // (with `law`'s contact law), warm start, then the solve to `solve`'s tolerance, each phase
  // timed into profile_.
  void solveContacts(double dt, const NscdSettings& law, const NscdSettings& solve, core::PhaseClock& clock) {
    broad_.findPairs(positionMid_, reach_, pairs_);
    clock.charge(Phase::UpdatePairs);
    collide();
    clock.charge(Phase::Collide);
    solver_.prepare(geometry_, positionMid_, inverse_, box_, walls_, dt, law);
    clock.charge(Phase::PrepareContacts);
    solver_.warmStart(cache_, geometry_, dt, velocity_);
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
    return h * (velocity_[i].v.norm() + velocity_[i].w.norm() * spinLever_[i]);
  }

  // Per-grain metric weights of the finisher (docs/model.md). The finisher's fixed point dq = 0 is
  // static equilibrium whatever the metric, so the weights change the path, not the packing.
  // After each step, a grain's weight is multiplied by
  // - d / trustRadius when its unscaled move d exceeded the trust radius, so that its next free
  //   move is about the trust radius and it does not scale the whole next step down again;
  // - 4 when its move reverses its last one without shrinking to less than half of it (a move
  //   above 1e-4 of the trust radius): with h = 1 t0 a pinacoid rocking between an edge and a face
  //   overshoots, a 2-cycle that grew by 6 % a step and never settled in 3,000 steps; a heavier
  //   grain takes a shorter step of its own. A reversal that halves the move is an approach that
  //   converges: weighed too, grains of a flat, sharp pinacoid pile grew heavy enough to move
  //   1e-5 d a step for 3,000 steps, where the same pile with fresh weights was at rest in 14;
  // - 1/2 when it moved less than a quarter of the trust radius, down to a weight of 1.
  void updateMetricWeight(int i, double d, double trustRadius) {
    BodyVelocity& last = lastMove_[i];
    const BodyVelocity& now = velocity_[i];
    const double r2 = spinLever_[i] * spinLever_[i];
    const double lastSize2 = last.v.squaredNorm() + r2 * last.w.squaredNorm();
    const double nowSize2 = now.v.squaredNorm() + r2 * now.w.squaredNorm();
    const bool reversed = last.v.dot(now.v) + r2 * last.w.dot(now.w) < 0.0 && d > 1e-4 * trustRadius &&
                          nowSize2 >= 0.25 * lastSize2;
    double factor = reversed ? 4.0 : 1.0;
    if (d > trustRadius)
      factor *= d / trustRadius;
    else if (d < 0.25 * trustRadius)
      factor *= 0.5;
    metricWeight_[i] = std::max(1.0, metricWeight_[i] * factor);
    last = now;
  }

  // q_m, the world inverse inertia there, and the free velocities. One thread: the loop is ~8%
  // of a step, and any OpenMP construct in this class (even a region never entered) makes the
  // compiled single-thread loop ~10-20% slower, for no measurable gain on 2 threads.
  void predict(double dt) {
    const double h = dt * (1.0 - settings_.theta);
    for (int i = 0; i < n_; ++i) {
      BodyVelocity& v = velocity_[i];
      const Mat3 r0 = orientation_[i].toRotationMatrix();
      const Vec3 angularMomentum = r0 * (inertiaBody_[i] * (r0.transpose() * v.w));
      positionMid_[i] = position_[i] + h * v.v;
      orientationMid_[i] = rotate(orientation_[i], v.w, h);
      const Mat3 rm = orientationMid_[i].toRotationMatrix();
      inverse_[i].invMass = invMass_[i];
      inverse_[i].invInertia = rm * invInertiaBody_[i] * rm.transpose();
      v.w = inverse_[i].invInertia * angularMomentum;
      v.v += dt * gravity_;
    }
  }

  // Damping (settings "damping" c, "damping_speed" v_d): the velocity and angular velocity of
  // every grain that carried a contact impulse in the last step and moves slower than v_d are
  // multiplied by exp(-c dt), before the free velocity.
  // The same factor for every loaded grain, so the relative velocity at a contact between two of
  // them scales alike and the contact problem keeps its structure. Rules that damp only unbalanced
  // motion cost more (a 188-pinacoid pile): Cundall's local damping (each velocity component cut
  // by alpha |its change|) 1.5 to 7 times the MPRGP iterations per step, damping only decelerating
  // grains (v . dv < 0) 1.2 to 2 times, and it settles more slowly.
  void damp(double factor) {
    const double speed2 = settings_.dampingSpeed * settings_.dampingSpeed;
    for (int i = 0; i < n_ && i < static_cast<int>(loaded_.size()); ++i) {
      if (!loaded_[i] || velocity_[i].v.squaredNorm() > speed2) continue;
      velocity_[i].v *= factor;
      velocity_[i].w *= factor;
    }
  }

  // Pair contacts in pair order, then wall contacts in grain order, whatever the thread count.
  void collide() { narrow_.collideAll(pairs_, positionMid_, orientationMid_, geometry_, threads_); }

  // q_{i+1} = q_m + dt theta v_{i+1}, wrapped into the box.
  void correct(double dt, double theta) {
    const double h = dt * theta;
    for (int i = 0; i < n_; ++i) {
      const BodyVelocity& v = velocity_[i];
      position_[i] = box_.wrap(positionMid_[i] + h * v.v);
      orientation_[i] = rotate(orientationMid_[i], v.w, h);
    }
  }

  void storeImpulses(double dt, double theta) {
    solver_.exportImpulses(geometry_, cacheBuffer_);
    cache_.replace(cacheBuffer_, dt);
    // Contact list: every contact that carries force or is closed. Objects (and their point
    // vectors) are reused from step to step, so the list costs no allocation in steady state.
    // The same pass records which grains carried an impulse, for damp() in the next step.
    std::size_t count = 0;
    const bool damping = settings_.damping > 0.0;
    if (damping) loaded_.assign(n_, 0);
    for (std::size_t c = 0; c < geometry_.size(); ++c) {
      const ContactGeometry& g = geometry_[c];
      bool loaded = false, closed = false;
      for (int p = 0; p < g.pointCount; ++p) {
        loaded |= solver_.normalImpulse(static_cast<int>(c), p) > 0.0;
        closed |= g.gaps[p] <= 0.0;
      }
      if (damping && loaded) {
        loaded_[g.a] = 1;
        if (g.b >= 0) loaded_[g.b] = 1;
      }
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
      const Vec3 unwrapped = positionMid_[g.a] + dt * theta * velocity_[g.a].v;
      const Vec3 shift = position_[g.a] - unwrapped;
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
      states_[i].position = position_[i];
      states_[i].orientation = orientation_[i];
      states_[i].velocity = velocity_[i].v;
      states_[i].angularVelocity = velocity_[i].w;
    }
  }

  core::BoxDef box_;
  core::WallMaterial walls_;
  Vec3 gravity_;
  NscdSettings settings_;
  int n_ = 0;
  // Cold data: mass properties in the body frame.
  std::vector<double> invMass_;
  std::vector<Mat3> inertiaBody_, invInertiaBody_;
  std::vector<double> reach_;
  std::vector<double> spinLever_;  // Grain::spinLever of each grain
  NscdSettings stepSolve_;      // settings_, or the fall's looser tolerance (startQuasiStaticFall)
  bool pinacoids_ = false;      // some grain is not a sphere
  NscdSettings finisherSettings_;
  bool lastFinisherStepClipped_ = false;
  bool finisherFellBack_ = false;  // fallBackToInteriorPoint() switched the finisher's solver
  // The finisher's per-grain metric weights and each grain's last move (updateMetricWeight()).
  std::vector<double> metricWeight_;
  std::vector<BodyVelocity> lastMove_;
  // State q_i (wrapped) and the predicted configuration q_m.
  std::vector<Vec3> position_, positionMid_;
  std::vector<Quat> orientation_, orientationMid_;
  // Hot solver state: velocities and inverse masses, one extra static body for the walls.
  std::vector<BodyVelocity> velocity_;
  std::vector<BodyInverseMass> inverse_;
  // Grains that carried a contact impulse in the last step (only with settings "damping" > 0;
  // filled by storeImpulses()).
  std::vector<char> loaded_;
  NarrowPhase narrow_;
  // Most OpenMP threads of a phase (the run's `threads`, SystemDef::threads): the broad and narrow
  // phases and MPRGP's passes each time their team against one thread and keep the faster
  // (thread_choice.hpp); results are the same bits for any value; NLGS stays sequential.
  int threads_ = 1;
  BroadPhase broad_;
  std::vector<CandidatePair> pairs_;
  std::vector<ContactGeometry> geometry_;
  ContactSolver solver_;
  ContactCache cache_;
  std::vector<CachedContact> cacheBuffer_;
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
