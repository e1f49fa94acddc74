#pragma once
// The fully resolved configuration of one run (STYLE "Configuration": definition structs with
// defaults and units, each with a JSON round trip so that a run writes back what it used).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "core/box.hpp"
#include "core/deposition.hpp"
#include "core/population.hpp"

namespace confpack::core {

/// Compaction under gravity (SPEC 4.3) and its stopping rule (SPEC 6.1).
struct CompactionDef {
  double dt = 0.0;                  ///< time step [t0]; 0 = SPEC 4 rule from the deposit's drop
  /// Adaptive time step: each step is the largest that keeps every grain within a hundredth of
  /// the smallest grain's size of motion (SPEC 4's d_L/100 for a monodisperse sample) at its
  /// current speed, gravity included, never below `dt` (or the SPEC 4 step) and at most
  /// kAdaptiveGrowth times the step before (apps/run_pipeline.hpp, AdaptiveTimeStep).
  bool adaptiveDt = false;
  double timeLimit = 400.0;         ///< simulated time after which the run stops unequilibrated [t0]
  int checkInterval = 200;          ///< steps between equilibrium checks [-]
  int frameInterval = 0;            ///< steps between ParaView frames; 0 = first and last only [-]
  double forceRatio = 1e-4;         ///< equilibrium: |sum F| < forceRatio d^2 P [-]
  double momentRatio = 1e-4;        ///< equilibrium: |sum M| < momentRatio d^3 P [-]
  double kineticRatio = 1e-8;       ///< equilibrium: E_k < kineticRatio d^3 P [-]
};

void to_json(nlohmann::json& j, const CompactionDef& c);
void from_json(const nlohmann::json& j, CompactionDef& c);

struct RunConfig {
  BoxDef box;
  PopulationDef population;
  DepositionDef deposition;
  CompactionDef compaction;
  std::string backend = "nscd";                              ///< "nscd" or "bullet"
  nlohmann::json backendOptions = nlohmann::json::object();  ///< backend-specific settings
  std::uint64_t seed = 1;                                    ///< every random stream derives from it
  int threads = 1;                                           ///< worker threads (OpenMP) [-]

  /// Throws std::invalid_argument with one clear message naming the bad field.
  void validate() const;
};

void to_json(nlohmann::json& j, const RunConfig& c);
void from_json(const nlohmann::json& j, RunConfig& c);

}  // namespace confpack::core
