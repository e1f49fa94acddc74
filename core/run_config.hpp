#pragma once
// The fully resolved configuration of one run: definition structs with
// defaults and units, each with a JSON round trip so that a run writes back what it used.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "core/box.hpp"
#include "core/population.hpp"
#include "core/walls.hpp"

namespace confpack::core {

/// Deposition (docs/model.md, "Deposition"): how many grains, for the box made for them.
struct DepositionDef {
  /// Solid fraction expected after compaction [-]. With the target height h it sets the grain
  /// volume to draw: V = phi_expected * L_x * W * h.
  double expectedSolidFraction = 0.60;
  /// Number of grains to deposit; 0 = derive it from the box height and expectedSolidFraction.
  std::size_t grainCount = 0;
  /// Largest number of grains a run may deposit [-]: a guard against a box typed a thousand times
  /// too large, refused before any work instead of failing out of memory. 1e6 is 33 times the
  /// paper's largest pile (30,400 grains), beyond what a run brings to rest in a day here.
  std::size_t maxGrains = 1'000'000;
  /// Most grains a run's box is made for [-]; 0 = no cap. A box whose height and expected solid
  /// fraction would hold more is shortened along x until it holds about this many
  /// (RunConfig::fitLengthToGrainCap), so that no run of a study outgrows the others (a run's
  /// cost grows faster than its grain count). Unlike max_grains, which refuses such a box.
  std::size_t grainCap = 0;

  /// Throws std::invalid_argument naming the bad field.
  void validate() const;
};

template <class T>
class SettingsTable;
/// The keys of DepositionDef (core/settings_table.hpp).
const SettingsTable<DepositionDef>& depositionTable();

void to_json(nlohmann::json& j, const DepositionDef& d);
void from_json(const nlohmann::json& j, DepositionDef& d);

/// How a compaction ends (docs/model.md, "Protocols").
enum class Protocol {
  Dynamic,      ///< Moreau-Jean (or Bullet) time steps until equilibrium or the time limit
  QuasiStatic,  ///< the same until the fall is over, then the quasi-static finisher (nscd only)
};

std::string toString(Protocol p);  ///< "dynamic", "quasi-static"

/// Largest accepted time_limit [t0]: 1e9 t0 is some 4e11 fixed steps, far beyond any compaction
/// (the slowest measured reached rest near 170 t0), and its step count stays exact in a long.
inline constexpr double kMaxTimeLimit = 1e9;

/// Time steps accepted besides 0 (the fixed step) [t0]. The fixed step moves a grain at most
/// d_L/100 a step, some 1e-3 to 7e-3 t0 (docs/model.md, "Time step"). Above 0.1 t0 a grain falling
/// at sqrt(g d_L) crosses a tenth of its size a step and contacts are missed (grains were thrown
/// through the floor); below 1e-6 t0 a compaction of 100 t0 is 1e8 steps, days of work that look
/// like a hang.
inline constexpr double kMinTimeStep = 1e-6;
inline constexpr double kMaxTimeStep = 0.1;
/// Compaction under gravity and its stopping rule (docs/model.md).
struct CompactionDef {
  /// Time step [t0]; 0 = the fixed step from the deposit's drop (docs/model.md, "Time step"),
  /// else in [kMinTimeStep, kMaxTimeStep].
  double dt = 0.0;
  /// Adaptive time step: each step is the largest that keeps every grain within a hundredth of
  /// the smallest grain's size of motion (d_L/100 for a monodisperse sample, as the fixed step)
  /// at its current speed, gravity included, never below `dt` (or the fixed step) and at most
  /// kAdaptiveGrowth times the step before (compaction/time_step.hpp, AdaptiveTimeStep).
  bool adaptiveDt = false;
  /// Simulated time after which the run stops unequilibrated [t0]; with the quasi-static
  /// protocol, after which the finisher takes over if the fall has not ended before. At most
  /// kMaxTimeLimit.
  double timeLimit = 400.0;
  /// Quasi-static protocol: the longest fall before the finisher takes over [t0]; 0 = time_limit.
  /// Apart from time_limit so that a study can give nscd's fall the time it needs and still stop
  /// Bullet, which has no finisher, at time_limit. At most kMaxTimeLimit.
  double fallTimeLimit = 0.0;
  int checkInterval = 200;     ///< steps between equilibrium checks [-]
  int frameInterval = 0;       ///< steps between ParaView frames; 0 = first and last only [-]
  double forceRatio = 1e-4;    ///< equilibrium: |sum F| < forceRatio d^2 P [-]
  double momentRatio = 1e-4;   ///< equilibrium: |sum M| < momentRatio d^3 P [-]
  double kineticRatio = 1e-8;  ///< equilibrium: E_k < kineticRatio d^3 P [-]
  Protocol protocol = Protocol::Dynamic;
  /// Quasi-static protocol: the dynamic steps hand over to the finisher at the first equilibrium
  /// check whose mean kinetic ratio E_k / (d^3 P) over the grains is below this [-]. 1e-4 is a
  /// grain of the bulk moving at about a hundredth of sqrt(g d): the fall is over, the pile
  /// creeps. The mean, not the largest: a lone grain sliding on the frictionless floor keeps the
  /// largest ratio up for ever (docs/model.md). Spheres count without their spin, which moves no
  /// boundary and which, once wall friction has spun a sphere, nothing stops.
  double switchKineticRatio = 1e-4;
  /// Quasi-static protocol: the largest motion of a grain's surface in one finisher step, as a
  /// fraction of the smallest grain's size [-]. A third of nscd's default alert distance (0.03):
  /// two grains closing on each other cannot cross the alert band unseen in one step.
  double trustRadius = 0.01;
  /// Quasi-static protocol: the finisher has converged when the equilibrium test holds and its last
  /// step moved no grain's surface more than this fraction of the smallest grain's size [-].
  double settleTolerance = 1e-6;
  /// Quasi-static protocol: the finisher's longest step [t0]. Its solves lose accuracy like
  /// h^2 (v_free = h g against dq / h); at 1 t0 a displacement of 1e-6 d already means a force
  /// imbalance a thousand times below the equilibrium criterion.
  double finisherMaxStep = 1.0;
  /// Quasi-static protocol: finisher steps after which the run stops unequilibrated [-].
  int finisherMaxSteps = 3000;
};

/// The keys of CompactionDef with units, ranges and meaning (core/settings_table.hpp): the JSON
/// reader and writer and the validation come from it.
const SettingsTable<CompactionDef>& compactionTable();
void to_json(nlohmann::json& j, const CompactionDef& c);
void from_json(const nlohmann::json& j, CompactionDef& c);

struct RunConfig {
  BoxDef box;
  WallMaterial walls;
  PopulationDef population;
  DepositionDef deposition;
  CompactionDef compaction;
  std::string backend = "nscd";                              ///< "nscd" or "bullet"
  nlohmann::json backendOptions = nlohmann::json::object();  ///< backend-specific settings
  std::uint64_t seed = 1;                                    ///< every random stream derives from it
  int threads = 1;                                           ///< worker threads (OpenMP) [-]

  /// Throws std::invalid_argument with one clear message naming the bad field, and refuses a
  /// deposit of more than deposition.max_grains grains (estimatedGrainCount()).
  void validate() const;
  /// What compaction::deposit would refuse only after starting, refused up front (std::invalid_argument):
  /// a box narrower or shorter than a grain's circumscribed diameter, or one whose height holds no
  /// grain. For a run that deposits; a run from a packing file takes its box and grains as given.
  void validateDeposit() const;
  /// grain_count, or the grains the box's target height holds at the expected solid fraction.
  double estimatedGrainCount() const;
  /// With deposition.grain_cap set (and no grain_count), shortens box.length_x, down to a multiple
  /// of 0.01 d_L, until estimatedGrainCount() <= grain_cap; never lengthens it, so a fitted
  /// configuration fits again unchanged. Throws std::invalid_argument when the box would be
  /// shorter than two large grains.
  void fitLengthToGrainCap();
};

/// The keys of RunConfig (config.json), its sections with their own tables (core/settings_table.hpp).
const SettingsTable<RunConfig>& runConfigTable();
void to_json(nlohmann::json& j, const RunConfig& c);
/// Reads the keys `j` gives over the defaults, each checked for its type and range (the rules
/// across keys are validate()'s); a box.wall_friction is read as walls.friction (withWallsMoved).
void from_json(const nlohmann::json& j, RunConfig& c);
/// A configuration written before the walls had their own object kept mu_w as box.wall_friction:
/// `j` with it moved to walls.friction (unchanged otherwise); throws if both are given. For a
/// document kept as JSON (a sweep file's base); from_json reads the same without copying.
nlohmann::json withWallsMoved(nlohmann::json j);

}  // namespace confpack::core
