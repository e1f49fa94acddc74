#include "backends/nscd/nscd_settings.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace confpack::nscd {

const core::SettingsTable<NscdSettings>& settingsTable() {
  using core::Range;
  using S = NscdSettings;
  static const core::SettingsTable<S> table = [] {
    core::SettingsTable<S> t("nscd");
    t.number("theta", &S::theta, Range::closed(0.5, 1.0), "-",
             "Moreau-Jean theta: 0.5 integrates free flight exactly, 1 is implicit Euler")
        .choice("solver", &S::solver,
                {{"mprgp", SolverKind::Mprgp}, {"nlgs", SolverKind::Nlgs}, {"ipm", SolverKind::Ipm}},
                "contact solver; its choice sets the defaults of tolerance and max_iterations")
        .choice(
            "finisher_solver", &S::finisherSolver,
            {{"auto", FinisherSolverKind::Auto},
             {"ipm", FinisherSolverKind::Ipm},
             {"mprgp", FinisherSolverKind::Mprgp}},
            "solver of the finisher's steps: auto = ipm for spheres; for pinacoids mprgp, then ipm once a solve ends "
            "at its cap (not between frictional walls); tolerance as for the steps")
        .choice("expansion", &S::expansion,
                {{"projected_cg", ExpansionKind::ProjectedCg}, {"gradient", ExpansionKind::Gradient}},
                "mprgp: the step taken when a conjugate gradient step would make an impulse negative")
        .choice("preconditioner", &S::preconditioner,
                {{"sgs", PreconditionerKind::SymmetricGaussSeidel},
                 {"none", PreconditionerKind::None},
                 {"cholesky", PreconditionerKind::Cholesky},
                 {"switching", PreconditionerKind::Switching}},
                "mprgp: symmetric Gauss-Seidel sweeps over the free rows, Jacobi scaling only, the shifted free "
                "block's exact inverse by a sparse Cholesky factorisation in body space, or sgs until a solve is "
                "dear, then cholesky")
        .number("preconditioner_switch", &S::preconditionerSwitch, Range::positive(), "-",
                "mprgp, switching: sgs iterations per normal row a solve may take before it goes on with cholesky")
        .number("preconditioner_shift", &S::preconditionerShift, Range::positive(), "-",
                "mprgp, cholesky and switching: the shift eps of (A_FF + eps I)^-1")
        .number("tolerance", &S::tolerance, Range::positive(), "-",
                "stopping threshold: mprgp and ipm relative projected gradient (1e-10), nlgs relative impulse change "
                "(1e-6)")
        .integer("max_iterations", &S::maxIterations, Range::atLeast(1), "-",
                 "iterations per step at most: mprgp 5000, nlgs 2000, ipm 200")
        .integer("min_iterations", &S::minIterations, Range::atLeast(1), "-",
                 "nlgs: sweeps done before testing convergence")
        .number("relaxation", &S::relaxation, Range::open(0.0, 2.0), "-", "nlgs: over-relaxation factor omega")
        .number("friction_relaxation", &S::frictionRelaxation, Range::open(0.0, 2.0), "-",
                "mprgp: over-relaxation factor of the tangential passes around side-wall friction")
        .number("alert_distance", &S::alertDistance, Range::atLeast(0.0), "d",
                "a pair closer than this (fraction of the smaller size) becomes a contact row")
        .number("gap_correction", &S::gapCorrection, Range::leftOpen(0.0, 1.0), "-",
                "fraction of an overlap removed per step")
        .number("max_correction_velocity", &S::maxCorrectionVelocity, Range::positive(), "sqrt(g d_L)",
                "largest separation velocity the overlap correction asks for")
        .choice("contact_law", &S::contactLaw, {{"gap", ContactLaw::Gap}, {"velocity", ContactLaw::Velocity}},
                "gap: an overlap is corrected by gap_correction; velocity: u_n + max(0, g/dt) >= 0, an overlap is "
                "held (LMGC90's IQS laws)")
        .choice("contact_detection", &S::contactDetection,
                {{"exact", ContactDetection::Exact}, {"common_plane", ContactDetection::CommonPlane}},
                "polyhedron contacts: every point its exact gap, or the vertices within a band of the common plane "
                "with one gap (LMGC90's reading)")
        .number("common_plane_band", &S::commonPlaneBand, Range::positive(), "-",
                "common_plane: vertices within max(0, g/2) + band x (half a grain size, along the normal) of the mid "
                "plane touch")
        .number("damping", &S::damping, Range::atLeast(0.0), "sqrt(g / d_L)", "damping rate of slow grains in contact")
        .numberOrNone("damping_speed", &S::dampingSpeed, Range::positive(), "sqrt(g d_L)",
                      "grains faster than this are not damped")
        .numberOrAuto("fall_tolerance", &S::fallTolerance, Range::positive(), "-",
                      "stopping threshold of the quasi-static protocol's fall: auto = 1e-6 for pinacoids, tolerance "
                      "for spheres")
        .rule([](const S& s) {
          if (s.minIterations > s.maxIterations)
            throw std::invalid_argument(fmt::format("nscd.min_iterations: must be at most max_iterations ({}) (got {})",
                                                    s.maxIterations, s.minIterations));
        });
    return t;
  }();
  return table;
}

void NscdSettings::validate() const {
  settingsTable().validate(*this);
}

void to_json(nlohmann::json& j, const NscdSettings& s) {
  j = settingsTable().write(s);
}

NscdSettings defaultsFor(SolverKind kind) {
  NscdSettings s;
  s.solver = kind;
  if (kind == SolverKind::Nlgs) {
    s.tolerance = 1e-6;
    s.maxIterations = 2000;
  } else if (kind == SolverKind::Ipm) {
    s.maxIterations = 200;  // Newton iterations: 20 to 60 per solve, whatever the conditioning
  }
  return s;
}

NscdSettings settingsFromJson(const nlohmann::json& j) {
  if (j.is_null()) return NscdSettings{};
  if (!j.is_object()) throw std::invalid_argument("nscd options must be a JSON object");
  // The solver first: it sets the defaults of the keys that depend on it.
  NscdSettings s;
  if (const auto it = j.find("solver"); it != j.end()) settingsTable().read({{"solver", *it}}, s);
  s = defaultsFor(s.solver);
  settingsTable().read(j, s);
  return s;
}

}  // namespace confpack::nscd
