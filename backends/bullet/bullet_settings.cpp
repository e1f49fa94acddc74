#include "backends/bullet/bullet_settings.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace confpack::bullet {

const core::SettingsTable<BulletSettings>& settingsTable() {
  using core::Range;
  using S = BulletSettings;
  static const core::SettingsTable<S> table = [] {
    core::SettingsTable<S> t("bullet");
    t.integer("iterations", &S::iterations, Range::atLeast(1), "-", "sequential-impulse sweeps per step at most")
        .number("residual_threshold", &S::residualThreshold, Range::atLeast(0.0), "-",
                "sweeps stop when the largest velocity correction is below this times |g| dt (0 = never early)")
        .flag("split_impulse", &S::splitImpulse, "correct deep overlaps with a push that adds no momentum")
        .number("split_impulse_penetration_threshold", &S::splitImpulsePenetrationThreshold, Range::atMost(0.0), "d_L",
                "overlaps deeper than this use the split impulse, shallower ones a Baumgarte bias")
        .number("split_impulse_turn_erp", &S::splitImpulseTurnErp, Range::closed(0.0, 1.0), "-",
                "fraction of the split-impulse turn applied to the orientation")
        .number("erp", &S::erp, Range::closed(0.0, 1.0), "-", "Baumgarte error reduction of shallow overlaps")
        .number("erp2", &S::erp2, Range::closed(0.0, 1.0), "-", "error reduction of the split-impulse push")
        .number("global_cfm", &S::globalCfm, Range::atLeast(0.0), "-", "constraint force mixing (0 = hard contact)")
        .number("sor", &S::sor, Range::open(0.0, 2.0), "-", "successive over-relaxation factor of every row")
        .number("linear_slop", &S::linearSlop, Range::atLeast(0.0), "d_L", "overlaps smaller than this are tolerated")
        .number("warm_starting_factor", &S::warmStartingFactor, Range::closed(0.0, 1.0), "-",
                "fraction of the last step's normal impulse each row starts from")
        .number("contact_breaking_threshold", &S::contactBreakingThreshold, Range::positive(), "d_L",
                "gap below which a manifold point is made and above which it is dropped")
        .integer("friction_directions", &S::frictionDirections, Range::closed(1.0, 2.0), "-",
                 "friction rows per contact point (2: a square Coulomb cone)")
        .flag("skip_zero_friction_rows", &S::skipZeroFrictionRows,
              "no friction rows where mu = 0 (same physics, faster)")
        .flag("sat_convex", &S::satConvex, "polyhedron contact normals by the separating-axis test instead of GJK/EPA")
        .integer("plane_perturbation_iterations", &S::planePerturbationIterations, Range::atLeast(0.0), "-",
                 "extra wall contact points of a polyhedron by small rotations")
        .integer("plane_perturbation_min_points", &S::planePerturbationMinPoints, Range::atLeast(0.0), "-",
                 "perturb only while the wall manifold has fewer points than this")
        .flag("randomize_order", &S::randomizeOrder, "random row order in every sweep (not bitwise reproducible)")
        .integer("manifolds_per_grain", &S::manifoldsPerGrain, Range::atLeast(1), "-",
                 "preallocated manifolds per grain");
    return t;
  }();
  return table;
}

void BulletSettings::validate() const {
  settingsTable().validate(*this);
}

void to_json(nlohmann::json& j, const BulletSettings& s) {
  j = settingsTable().write(s);
}

BulletSettings bulletSettingsFromJson(const nlohmann::json& j) {
  BulletSettings s;
  if (j.is_null()) return s;
  if (!j.is_object()) throw std::invalid_argument("bullet options must be a JSON object");
  settingsTable().read(j, s);
  return s;
}

}  // namespace confpack::bullet
