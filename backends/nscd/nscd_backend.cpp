#include "backends/nscd/nscd_backend.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <utility>
#include <stdexcept>

#include "backends/nscd/broad_phase.hpp"
#include "backends/nscd/contact_cache.hpp"
#include "backends/nscd/contact_solver.hpp"
#include "backends/nscd/narrow_phase.hpp"
#include "backends/nscd/nscd_settings.hpp"
#include "backends/nscd/quasi_static_solver.hpp"

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

class Stopwatch {
 public:
  /// Seconds since the last call (or construction).
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// Moreau-Jean theta time stepping (SPEC 5.1):
//   v_free  = v_i + dt g                      (gravity is the only external force)
//   q_m     = q_i + dt (1 - theta) v_i        (contacts are detected here)
//   v_{i+1} = v_free + M^-1 H r               (r from the Gauss-Seidel solver)
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
        gravity_(system.gravity),
        settings_(settings),
        n_(static_cast<int>(system.grains.size())),
        narrow_(system.box, system.grains, settings.alertDistance),
        broad_(system.box, n_ > 0 ? narrow_.maxReach() : 1.0, settings.threads) {
    box_.validate();
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
      radius_.push_back(g.boundingRadius());
      spheres_.push_back(g.shape == core::ShapeKind::Sphere);
    }
    // The finisher's contact problem (quasiStaticStep): implicit Euler (theta = 1), so that the
    // displacement h v is the one the linearised gaps constrain, and overlaps removed whole.
    finisherSettings_ = settings_;
    finisherSettings_.theta = 1.0;
    finisherSettings_.gapCorrection = 1.0;
    finisherSettings_.maxCorrectionVelocity = std::numeric_limits<double>::infinity();
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
    Stopwatch clock;
    if (settings_.damping > 0.0) damp(std::exp(-settings_.damping * dt));
    predict(dt);
    profile_[Phase::Integrate] += clock.lap();
    broad_.findPairs(positionMid_, reach_, pairs_);
    profile_[Phase::UpdatePairs] += clock.lap();
    collide();
    profile_[Phase::Collide] += clock.lap();
    solver_.prepare(geometry_, positionMid_, inverse_, box_, dt, settings_);
    profile_[Phase::PrepareContacts] += clock.lap();
    solver_.warmStart(cache_, geometry_, dt, velocity_);
    profile_[Phase::WarmStart] += clock.lap();
    profile_.iterations = solver_.solve(velocity_, settings_);
    profile_.residual = solver_.residual();
    profile_.contactPoints = solver_.rowCount();
    profile_[Phase::Solve] += clock.lap();
    correct(dt, settings_.theta);
    profile_[Phase::Integrate] += clock.lap();
    storeImpulses(dt, settings_.theta);
    profile_[Phase::StoreImpulses] += clock.lap();
  }

  bool hasQuasiStaticStep() const override { return true; }

  // The Moreau-Jean step from rest with theta = 1: v_free = h g, the contact law with the gaps
  // closed exactly, then dq = h v_{i+1}: the minimiser of 1/2 dq.D dq / h^2 - F_ext.dq under the
  // linearised non-penetration constraints (docs/model.md, "Quasi-static compaction").
  // Frictionless boxes: the direct solver (quasi_static_solver.hpp), with D = diag(mu_i M_i), each
  // grain's mass scaled by a metric weight mu_i >= 1 (metric_). The fixed point dq = 0,
  // F_ext + J^T lambda = 0, does not depend on D, only the path there does: a grain that moved
  // more than half the trust radius (one falling into a cavity, one pushed through a rearranging
  // cage) is made heavier for the next step in proportion, so that it alone, and not the whole
  // pile through the trust radius, takes short steps; weights halve again once the grain moves
  // less than an eighth of it. A factorisation does not mind the spread of the weights; MPRGP
  // does (its iterations grow with the conditioning), so that path keeps D = M.
  // Side-wall friction: MPRGP with the tangential impulses (the Coulomb law on the tangential
  // displacement of the step), the same block Gauss-Seidel as a dynamic step. After a step that
  // the trust radius cut, that solve stops at kRoughTolerance: such a step is a descent
  // direction, not an equilibrium; an overlap it leaves is removed whole by the next step.
  core::QuasiStaticMove quasiStaticStep(double h, double trustRadius) override {
    if (!(h > 0.0) || !std::isfinite(h)) throw std::invalid_argument("nscd: quasi-static step h must be positive");
    if (!(trustRadius > 0.0)) throw std::invalid_argument("nscd: quasi-static trust radius must be positive");
    profile_ = core::StepProfile{};
    Stopwatch clock;
    const bool direct = !box_.hasFrictionalWalls();
    metric_.resize(n_, 1.0);
    for (int i = 0; i < n_; ++i) velocity_[i] = BodyVelocity{};
    predict(h);  // from rest: q_m = q_i, v_free = h g
    profile_[Phase::Integrate] += clock.lap();
    broad_.findPairs(positionMid_, reach_, pairs_);
    profile_[Phase::UpdatePairs] += clock.lap();
    collide();
    profile_[Phase::Collide] += clock.lap();
    if (direct) {
      solveFinisherDirect(h);
    } else {
      solver_.prepare(geometry_, positionMid_, inverse_, box_, h, finisherSettings_);
      profile_[Phase::PrepareContacts] += clock.lap();
      solver_.warmStart(cache_, geometry_, h, velocity_);
      profile_[Phase::WarmStart] += clock.lap();
      NscdSettings solve = finisherSettings_;
      if (lastFinisherStepClipped_) solve.tolerance = std::max(solve.tolerance, kRoughTolerance);
      profile_.iterations = solver_.solve(velocity_, solve);
      profile_.residual = solver_.residual();
      profile_.contactPoints = solver_.rowCount();
    }
    profile_[Phase::Solve] += clock.lap();
    core::QuasiStaticMove move;
    const double target = 0.5 * trustRadius;
    for (int i = 0; i < n_; ++i) {
      const double d = h * (velocity_[i].v.norm() + velocity_[i].w.norm() * radius_[i]);
      move.maxDisplacement = std::max(move.maxDisplacement, d);
      if (!direct) continue;
      if (d > target)
        metric_[i] *= d / target;
      else if (d < 0.125 * trustRadius)
        metric_[i] = std::max(1.0, 0.5 * metric_[i]);
    }
    // Scaling the whole step keeps it inside the linearised constraints (they are convex and
    // dq = 0 satisfies those of the contacts that are not overlapping).
    if (move.maxDisplacement > trustRadius) {
      const double s = trustRadius / move.maxDisplacement;
      for (int i = 0; i < n_; ++i) {
        velocity_[i].v *= s;
        velocity_[i].w *= s;
      }
      move.maxDisplacement = trustRadius;
      move.clipped = true;
    }
    lastFinisherStepClipped_ = move.clipped;
    correct(h, 1.0);
    profile_[Phase::Integrate] += clock.lap();
    if (direct) {
      storeContacts(h, 1.0, [&](int c, int p) { return std::pair{finisherImpulse_[rowOf_[c] + p], Vec3(Vec3::Zero())}; });
      cacheBuffer_.clear();
      for (std::size_t c = 0; c < geometry_.size(); ++c) {
        CachedContact e;
        e.key = ContactKey::of(geometry_[c]);
        e.pointCount = geometry_[c].pointCount;
        for (int p = 0; p < e.pointCount; ++p) e.normal[p] = finisherImpulse_[rowOf_[c] + p];
        cacheBuffer_.push_back(e);
      }
      cache_.replace(cacheBuffer_, h);
    } else {
      storeImpulses(h, 1.0);
    }
    profile_[Phase::StoreImpulses] += clock.lap();
    return move;
  }

  // The finisher's frictionless problem by the direct solver; leaves v = dq / h in velocity_ and
  // the impulses (force x h) per point in finisherImpulse_ (rowOf_[c] + p).
  void solveFinisherDirect(double h) {
    bool rotations = false;
    for (int i = 0; i < n_ && !rotations; ++i) rotations = !spheres_[i];
    finisherBodies_.resize(n_);
    for (int i = 0; i < n_; ++i) {
      QuasiStaticSolver::Body& b = finisherBodies_[i];
      const double m = 1.0 / invMass_[i];
      b.mass = metric_[i] * m;
      b.force = m * gravity_;
      if (rotations) {
        const Mat3 r = orientationMid_[i].toRotationMatrix();
        b.inertia = metric_[i] * (r * inertiaBody_[i] * r.transpose());
      }
    }
    rowOf_.resize(geometry_.size());
    warmForces_.clear();
    std::size_t cursor = 0;
    for (std::size_t c = 0; c < geometry_.size(); ++c) {
      const ContactGeometry& g = geometry_[c];
      rowOf_[c] = static_cast<int>(warmForces_.size());
      const CachedContact* e = cache_.dt() > 0.0 ? cache_.find(ContactKey::of(g), cursor) : nullptr;
      for (int p = 0; p < g.pointCount; ++p)
        warmForces_.push_back(e && e->pointCount == g.pointCount ? e->normal[p] / cache_.dt() : 0.0);
    }
    const QuasiStaticSolver::Outcome o = finisherSolver_.solve(geometry_, positionMid_, finisherBodies_, box_, rotations,
                                                               h, warmForces_, finisherMove_, finisherTurn_,
                                                               finisherImpulse_);
    for (double& r : finisherImpulse_) r *= h;
    for (int i = 0; i < n_; ++i) {
      velocity_[i].v = finisherMove_[i] / h;
      velocity_[i].w = finisherTurn_[i] / h;
    }
    profile_.iterations = o.newtonIterations;
    profile_.residual = o.infeasibility;
    profile_.contactPoints = static_cast<int>(warmForces_.size());
  }

  // q_m, the world inverse inertia there, and the free velocities. One thread: the loop is ~8%
  // of a step, and any OpenMP construct in this class (even a region never entered) was
  // measured to make the compiled single-thread loop ~10-20% slower; a gain on 2 threads could
  // not be shown on the shared machine.
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
  // them scales alike and the contact problem keeps its structure. Two rules that damp only
  // unbalanced motion were tried first on the 188-pinacoid pile and dropped: Cundall's local
  // damping (each velocity component cut by alpha |its change|, per component or along v) took
  // 1.5 to 7 times more MPRGP iterations per step, and damping only decelerating grains
  // (v . dv < 0) 1.2 to 2 times more while settling more slowly than this rule.
  void damp(double factor) {
    const double speed2 = settings_.dampingSpeed * settings_.dampingSpeed;
    for (int i = 0; i < n_ && i < static_cast<int>(loaded_.size()); ++i) {
      if (!loaded_[i] || velocity_[i].v.squaredNorm() > speed2) continue;
      velocity_[i].v *= factor;
      velocity_[i].w *= factor;
    }
  }

  // Pair contacts in pair order, then wall contacts in grain order, whatever the thread count.
  void collide() { narrow_.collideAll(pairs_, positionMid_, orientationMid_, geometry_, settings_.threads); }

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
    storeContacts(dt, theta, [this](int c, int p) {
      return std::pair{solver_.normalImpulse(c, p), solver_.tangentImpulse(c, p)};
    });
  }

  // The contact list of the step from the impulses impulse(c, p) = {normal, tangential vector}.
  template <class Impulse>
  void storeContacts(double dt, double theta, const Impulse& impulse) {
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
        loaded |= impulse(static_cast<int>(c), p).first > 0.0;
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
        const auto [normal, tangent] = impulse(static_cast<int>(c), p);
        cp.normalForce = normal / dt;
        cp.tangentForce = tangent / dt;
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
  Vec3 gravity_;
  NscdSettings settings_;
  int n_ = 0;
  // Cold data: mass properties in the body frame.
  std::vector<double> invMass_;
  std::vector<Mat3> inertiaBody_, invInertiaBody_;
  std::vector<double> reach_;
  std::vector<double> radius_;  // bounding radius: a grain's surface moves at most |v| + |w| radius
  NscdSettings finisherSettings_;
  bool lastFinisherStepClipped_ = false;
  // The finisher's direct path (quasiStaticStep, solveFinisherDirect).
  std::vector<double> metric_;  // mu_i, the metric weights
  std::vector<char> spheres_;   // grain i is a sphere
  QuasiStaticSolver finisherSolver_;
  std::vector<QuasiStaticSolver::Body> finisherBodies_;
  std::vector<int> rowOf_;
  std::vector<double> warmForces_, finisherImpulse_;
  std::vector<Vec3> finisherMove_, finisherTurn_;
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
  return std::make_unique<NscdBackend>(system, settingsFromJson(options));
}

}  // namespace confpack::nscd
