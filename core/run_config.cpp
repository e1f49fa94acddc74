#include "core/run_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string_view>

#include "core/backend.hpp"
#include "core/json_input.hpp"
#include "core/settings_table.hpp"

namespace confpack::core {

using nlohmann::json;

std::string toString(Protocol p) {
  return p == Protocol::QuasiStatic ? "quasi-static" : "dynamic";
}

const SettingsTable<DepositionDef>& depositionTable() {
  using D = DepositionDef;
  static const SettingsTable<D> table = [] {
    SettingsTable<D> t("deposition");
    t.number("expected_solid_fraction", &D::expectedSolidFraction, Range::open(0.0, 1.0), "-",
             "solid fraction expected after compaction; with the height it sets the volume of grains drawn")
        .integer("grain_count", &D::grainCount, Range::atLeast(0.0), "-",
                 "grains to deposit; 0 = from the height and expected_solid_fraction")
        .integer("max_grains", &D::maxGrains, Range::atLeast(1.0), "-",
                 "largest number of grains a run may deposit (a guard against a mistyped box)")
        .integer("grain_cap", &D::grainCap, Range::atLeast(0.0), "-",
                 "most grains a box is made for: a larger box is shortened along x (length_x) to hold about "
                 "this many; 0 = no cap");
    return t;
  }();
  return table;
}

void DepositionDef::validate() const {
  depositionTable().validate(*this);
}

void to_json(nlohmann::json& j, const DepositionDef& d) {
  j = depositionTable().write(d);
}

void from_json(const nlohmann::json& j, DepositionDef& d) {
  DepositionDef out;
  depositionTable().read(j, out);
  d = out;
}

const SettingsTable<CompactionDef>& compactionTable() {
  using C = CompactionDef;
  static const SettingsTable<C> table = [] {
    SettingsTable<C> t("compaction");
    t.number("dt", &C::dt, Range::closed(0.0, kMaxTimeStep), "t0",
             "time step; 0 = the fixed step from the deposit's drop, else at least 1e-6")
        .flag("adaptive_dt", &C::adaptiveDt, "adaptive time step, never below dt")
        .number("time_limit", &C::timeLimit, Range::leftOpen(0.0, kMaxTimeLimit), "t0",
                "simulated time after which the run stops unequilibrated (quasi-static: the fall hands over)")
        .number("fall_time_limit", &C::fallTimeLimit, Range::closed(0.0, kMaxTimeLimit), "t0",
                "quasi-static: the longest fall before the finisher takes over; 0 = time_limit")
        .integer("check_interval", &C::checkInterval, Range::atLeast(1), "-", "steps between equilibrium checks")
        .integer("frame_interval", &C::frameInterval, Range::atLeast(0), "-",
                 "steps between ParaView frames; 0 = first and last only")
        .number("force_ratio", &C::forceRatio, Range::positive(), "-", "equilibrium: |sum F| < force_ratio d^2 P")
        .number("moment_ratio", &C::momentRatio, Range::positive(), "-", "equilibrium: |sum M| < moment_ratio d^3 P")
        .number("kinetic_ratio", &C::kineticRatio, Range::positive(), "-", "equilibrium: E_k < kinetic_ratio d^3 P")
        .choice("protocol", &C::protocol, {{"dynamic", Protocol::Dynamic}, {"quasi-static", Protocol::QuasiStatic}},
                "time steps to equilibrium, or time steps until the fall is over then the finisher")
        .number("switch_kinetic_ratio", &C::switchKineticRatio, Range::positive(), "-",
                "quasi-static: hand over when the mean kinetic ratio is below this")
        .number("trust_radius", &C::trustRadius, Range::leftOpen(0.0, 0.5), "smallest grain size",
                "quasi-static: largest motion of a grain's surface in one finisher step")
        .number("settle_tolerance", &C::settleTolerance, Range::positive(), "smallest grain size",
                "quasi-static: the finisher has converged when its last step moved no grain more")
        .number("finisher_max_step", &C::finisherMaxStep, Range::positive(), "t0",
                "quasi-static: longest finisher step")
        .integer("finisher_max_steps", &C::finisherMaxSteps, Range::atLeast(1), "-",
                 "quasi-static: finisher steps after which the run stops unequilibrated");
    return t;
  }();
  return table;
}

void to_json(json& j, const CompactionDef& c) {
  j = compactionTable().write(c);
}

void from_json(const json& j, CompactionDef& c) {
  c = CompactionDef{};
  compactionTable().read(j, c);
}

const SettingsTable<RunConfig>& runConfigTable() {
  using R = RunConfig;
  static const SettingsTable<R> table = [] {
    SettingsTable<R> t("config");
    t.section("box", &R::box, &boxTable, "the box's geometry")
        .section("walls", &R::walls, &wallMaterialTable, "the walls' material")
        .section("population", &R::population, &populationTable, "the grains' shape and sizes")
        .section("deposition", &R::deposition, &depositionTable, "the geometric deposition")
        .section("compaction", &R::compaction, &compactionTable, "time steps, protocol and equilibrium test")
        .field(
            "backend", "-", "\"nscd\" or \"bullet\"", "contact backend",
            [](const json& j, R& c) {
              if (!j.is_string())
                throw std::invalid_argument(
                    fmt::format("config.backend: must be a string (got {})", jsonExcerpt(j, 40)));
              c.backend = j.get<std::string>();
            },
            [](const R& c) { return json(c.backend); },
            [](const R& c) {
              if (std::find(kBackendNames.begin(), kBackendNames.end(), c.backend) == kBackendNames.end())
                throw std::invalid_argument("backend: " + unknownBackendMessage(c.backend));
            })
        .field(
            "backend_options", "-", "an object (`confpack options nscd`, `confpack options bullet`)",
            "the backend's settings, checked by the backend", [](const json& j, R& c) { c.backendOptions = j; },
            [](const R& c) { return c.backendOptions; },
            [](const R& c) {
              if (!c.backendOptions.is_object())
                throw std::invalid_argument(
                    fmt::format("backend_options: must be a JSON object (got {})", jsonExcerpt(c.backendOptions)));
            })
        .integer("seed", &R::seed, Range::atLeast(0.0), "-", "every random stream derives from it")
        .integer("threads", &R::threads, Range::atLeast(1.0), "-", "worker threads (OpenMP) of the run");
    return t;
  }();
  return table;
}

void to_json(json& j, const RunConfig& c) {
  j = runConfigTable().write(c);
}

namespace {

bool hasLegacyWallFriction(const json& j) {
  return j.is_object() && j.contains("box") && j.at("box").is_object() && j.at("box").contains("wall_friction");
}

void refuseWallFrictionTwice(const json& j) {
  if (j.contains("walls") && j.at("walls").is_object() && j.at("walls").contains("friction"))
    throw std::invalid_argument("box.wall_friction: given twice, as walls.friction too (keep walls.friction)");
}

}  // namespace

json withWallsMoved(json j) {
  if (!hasLegacyWallFriction(j)) return j;
  refuseWallFrictionTwice(j);
  json& walls = j["walls"];
  if (walls.is_null()) walls = json::object();
  if (walls.is_object()) walls["friction"] = j["box"]["wall_friction"];
  j["box"].erase("wall_friction");
  return j;
}

// The rules across fields are RunConfig::validate()'s. Key by key, never copying `j`: a value may
// be nested deeper than a recursive copy's stack allows.
void from_json(const json& j, RunConfig& c) {
  c = RunConfig{};
  const SettingsTable<RunConfig>& table = runConfigTable();
  if (!hasLegacyWallFriction(j)) return table.readKeys(j, c);
  refuseWallFrictionTwice(j);  // mu_w as written before the walls had their own object
  for (const auto& [key, value] : j.items()) {
    if (key != "box") {
      table.readKey(key, value, c);
      continue;
    }
    for (const auto& [k, v] : value.items())
      if (k == "wall_friction")
        readLegacyWallFriction(v, c.walls);
      else
        boxTable().readKey(k, v, c.box);
  }
}

void RunConfig::validate() const {
  runConfigTable().validate(*this);
  if (compaction.dt > 0.0 && compaction.dt < kMinTimeStep)
    throw std::invalid_argument(fmt::format(
        "compaction.dt: {} is below {:g} t0 (0 takes the fixed step); a compaction of 100 t0 would take more than "
        "1e8 steps",
        numberText(compaction.dt), kMinTimeStep));
  const double grains = estimatedGrainCount();
  if (grains > static_cast<double>(deposition.maxGrains))
    throw std::invalid_argument(fmt::format(
        "deposition: about {:.3g} grains for this box, more than max_grains ({}); check the box's size, or raise "
        "the limit with --max-grains (deposition.max_grains)",
        grains, deposition.maxGrains));
}

void RunConfig::validateDeposit() const {
  const double diameter = population.maxCircumscribedDiameter();
  const std::pair<double, const char*> lengths[] = {{box.lengthX, "box.length_x"}, {box.width, "box.width"}};
  for (const auto& [length, name] : lengths)
    if (length < diameter)
      throw std::invalid_argument(
          fmt::format("{}: {:g} d_L is less than a grain's circumscribed diameter ({:g} d_L): no grain fits", name,
                      length, diameter));
  if (deposition.grainCount > 0) return;
  // drawGrains stops each size class at the count whose volume is nearest its share: none when
  // the share is under half a grain.
  const double volume = deposition.expectedSolidFraction * box.lengthX * box.width * box.height;
  const double small = population.smallFraction / 100.0;
  const bool noLarge = volume * (1.0 - small) < 0.5 * population.meanGrainVolume(population.largeSize);
  const bool noSmall = volume * small < 0.5 * population.meanGrainVolume(population.smallSize);
  if (noLarge && noSmall)
    throw std::invalid_argument(fmt::format(
        "box.height: a box of {:g} x {:g} x {:g} d_L at expected_solid_fraction {:g} holds no grain; raise the "
        "height or give grain_count",
        box.lengthX, box.width, box.height, deposition.expectedSolidFraction));
}

double RunConfig::estimatedGrainCount() const {
  if (deposition.grainCount > 0) return static_cast<double>(deposition.grainCount);
  const double volume = deposition.expectedSolidFraction * box.lengthX * box.width * box.height;
  const double small = population.smallFraction / 100.0;
  return volume * (1.0 - small) / population.meanGrainVolume(population.largeSize) +
         (small > 0.0 ? volume * small / population.meanGrainVolume(population.smallSize) : 0.0);
}

void RunConfig::fitLengthToGrainCap() {
  if (deposition.grainCap == 0 || deposition.grainCount > 0) return;
  const double grains = estimatedGrainCount();
  const double cap = static_cast<double>(deposition.grainCap);
  if (grains <= cap) return;
  // The count is proportional to length_x; rounded down so that it stays under the cap.
  const double fitted = std::floor(box.lengthX * cap / grains * 100.0) / 100.0;
  const double shortest = 2.0 * population.largeSize;
  if (fitted < shortest)
    throw std::invalid_argument(fmt::format(
        "deposition.grain_cap: {} grains fit in a length_x of {:.3g} d_L, shorter than two large grains ({:.3g}); "
        "raise the cap or make the box narrower or lower",
        deposition.grainCap, fitted, shortest));
  box.lengthX = fitted;
}

}  // namespace confpack::core
