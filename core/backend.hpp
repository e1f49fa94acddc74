#pragma once
// The contact backend interface (docs/model.md, "Contact backends"). Deposition, the run
// pipeline and analysis only see this; `makeBackend("nscd" | "bullet", ...)` in
// backends/backend_factory.hpp picks the implementation.
//
// A backend is built once from a SystemDef (grains at rest, boundaries, gravity), advanced with
// step(dt), and after every step exposes the poses and velocities, the contact list of that
// step (forces = impulse / dt, conventions in core/contact.hpp) and a StepProfile.
#include <array>
#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "core/box.hpp"
#include "core/contact.hpp"
#include "core/grain.hpp"
#include "core/walls.hpp"

namespace confpack::core {

/// Names of the contact backends, in a stable order; backends/backend_factory.hpp builds one by
/// name. Here so that what only checks a name (a run configuration, a sweep file) needs no backend.
inline constexpr std::array<std::string_view, 2> kBackendNames = {"nscd", "bullet"};

/// "unknown backend 'NAME' (expected nscd or bullet)", the name cut to 40 characters (it may be
/// any text of a configuration file): the one refusal of a name not in kBackendNames.
std::string unknownBackendMessage(std::string_view name);

/// Everything a backend needs to build its world.
struct SystemDef {
  BoxDef box;
  WallMaterial walls;                   ///< the walls' friction (RunConfig::walls)
  std::vector<Grain> grains;            ///< initial poses; velocities start at zero
  Vec3 gravity = Vec3(0.0, 0.0, -1.0);  ///< [g]
  double density = 1.0;                 ///< grain density rho
  int threads = 1;                      ///< OpenMP threads the backend may use (RunConfig::threads) [-]
};

struct BodyState {
  Vec3 position = Vec3::Zero();  ///< centroid, wrapped into the box [d_L]
  Quat orientation = Quat::Identity();
  Vec3 velocity = Vec3::Zero();         ///< [sqrt(g d_L)]
  Vec3 angularVelocity = Vec3::Zero();  ///< world frame [1/t0]
};

/// Named phases of one step (after Box2D's solver stages), the same for both backends so that
/// they compare phase by phase. Each backend's step() is the list of its phase functions, timed
/// by one PhaseClock; a backend fills the phases it has and leaves the others at zero. What each
/// backend does in each phase: docs/performance.md, "The phases of a step".
enum class Phase : int {
  UpdatePairs,      ///< broad phase: candidate pairs, periodic images included
  Collide,          ///< narrow phase: contact points, normals, gaps
  PrepareContacts,  ///< constraint rows (Delassus blocks, frames)
  WarmStart,        ///< cached impulses applied (Bullet: inside PrepareContacts)
  Solve,            ///< the contact solver's iterations
  Integrate,        ///< free velocities, then positions
  StoreImpulses,    ///< impulses kept for the next step, contact list, states
  Count
};

std::string_view toString(Phase p);  ///< "update_pairs", "collide", ... (JSON keys)

struct StepProfile {
  std::array<double, static_cast<int>(Phase::Count)> seconds{};  ///< wall time of each phase [s]
  int iterations = 0;                                            ///< Gauss-Seidel sweeps or solver iterations this step
  double residual = 0.0;  ///< final convergence measure of the solver (backend-defined, documented)
  int contactPoints = 0;  ///< active contact points (rows) solved this step
  double& operator[](Phase p) { return seconds[static_cast<int>(p)]; }
  double operator[](Phase p) const { return seconds[static_cast<int>(p)]; }
  double total() const {
    double s = 0.0;
    for (double t : seconds) s += t;
    return s;
  }
};

/// Times the phases of one step into a StepProfile: each charge(p) adds the wall time since the
/// clock was made or last charged to phase p, so consecutive phases cover the step without gaps.
class PhaseClock {
 public:
  explicit PhaseClock(StepProfile& profile) : profile_(&profile), last_(std::chrono::steady_clock::now()) {}
  void charge(Phase p) {
    const auto now = std::chrono::steady_clock::now();
    (*profile_)[p] += std::chrono::duration<double>(now - last_).count();
    last_ = now;
  }

 private:
  StepProfile* profile_;
  std::chrono::steady_clock::time_point last_;
};

/// What one quasi-static step did (ContactBackend::quasiStaticStep).
struct QuasiStaticMove {
  double maxDisplacement = 0.0;  ///< largest displacement of a grain's surface in the step taken [d_L]
  bool clipped = false;          ///< the trust radius shortened some grain's displacement
};

class ContactBackend {
 public:
  virtual ~ContactBackend() = default;
  /// "nscd" or "bullet".
  virtual std::string_view name() const = 0;
  /// Advances the system by dt [t0].
  virtual void step(double dt) = 0;
  /// Poses and velocities after the last step, one per grain, in the SystemDef's order.
  virtual const std::vector<BodyState>& states() const = 0;
  /// Contacts of the last step with their forces.
  virtual const std::vector<Contact>& contacts() const = 0;
  /// Timing and solver statistics of the last step.
  virtual const StepProfile& profile() const = 0;
  /// The fully resolved solver settings (written into result.json).
  virtual nlohmann::json settings() const = 0;

  /// Whether quasiStaticStep() is implemented (the quasi-static finisher, docs/model.md).
  virtual bool hasQuasiStaticStep() const { return false; }
  /// One step of the quasi-static finisher: every velocity set to zero, then the implicit Euler
  /// step of length h [t0] from rest, i.e. the displacement dq solving
  ///     min 1/2 dq.M dq / h^2 - F_ext.dq   subject to  gap + J dq >= 0  (contacts re-detected),
  /// whose multipliers are the contact forces; when some grain's surface would move more than
  /// `trustRadius` [d_L], the whole step is scaled down so that it moves that far. States and
  /// contacts are then those of a step (velocities dq / h, forces = impulse / h). Only backends
  /// with hasQuasiStaticStep() implement it; the others throw std::logic_error.
  virtual QuasiStaticMove quasiStaticStep(double h, double trustRadius);
  /// Says that the step()s that follow are the quasi-static protocol's fall, whose last state the
  /// finisher balances: a backend may then solve them less tightly (nscd's fall_tolerance).
  /// Called only on backends with hasQuasiStaticStep(), before their first step.
  virtual void startQuasiStaticFall() {}
  /// How the finisher solved its steps, for result.json's timing.stages.quasi_static (nscd:
  /// "solver", that of its last step, and "switched_from_mprgp"); an empty object by default.
  virtual nlohmann::json finisherReport() const { return nlohmann::json::object(); }

  /// The state after the last step, for a run's checkpoint (docs/model.md, "Checkpoints"): every
  /// grain's pose and velocity (bodyStatesToJson), and whatever else the next step reads (nscd: the
  /// warm-start impulses and the finisher's metric weights). Doubles are written with 17
  /// significant digits, so they read back to the same bits.
  virtual nlohmann::json saveState() const;
  /// Takes back a state saveState() wrote, on a backend built from the same SystemDef with the
  /// grains at the saved poses. Throws std::invalid_argument when the state does not fit.
  /// The steps that follow are the same bits as without the interruption when exactRestore().
  virtual void restoreState(const nlohmann::json& state) = 0;
  /// Whether restoreState() gives back everything a step reads (nscd: yes; Bullet: no, its
  /// contact manifolds and their warm-start impulses are rebuilt from the poses).
  virtual bool exactRestore() const { return false; }
};

/// Poses and velocities as JSON, one array [x y z qw qx qy qz vx vy vz wx wy wz] per grain.
nlohmann::json bodyStatesToJson(const std::vector<BodyState>& states);
/// The reverse of bodyStatesToJson; throws std::invalid_argument unless `j` holds exactly `count`
/// such arrays of finite numbers.
std::vector<BodyState> bodyStatesFromJson(const nlohmann::json& j, std::size_t count);

}  // namespace confpack::core
