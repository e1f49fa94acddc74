#include "study/reproduce.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace confpack::study {

using nlohmann::json;

const std::vector<std::string_view>& reproductionScales() {
  static const std::vector<std::string_view> s = {"tiny", "quick", "medium", "paper"};
  return s;
}

namespace {

// The three families of the confinement study (docs/model.md, "The study and its report") as groups
// of one sweep file. Values that do not vary within a group are given as one-element lists so that
// the file reads as the study's definition.
json studyGroups(const json& widths, const json& fractions, const json& frictions, int replicas, bool pinacoids) {
  const json backends = {"nscd", "bullet"};
  json groups = json::array();
  // Spheres, mono- and bidisperse, frictionless walls: phi(W), Z(W), profiles, lambda_L(x_S).
  groups.push_back({{"shape", {"sphere"}},
                    {"small_fraction", fractions},
                    {"width", widths},
                    {"wall_friction", {0.0}},
                    {"replicas", replicas},
                    {"backend", backends}});
  // Wall friction (docs/model.md, "Wall friction"), monodisperse spheres, confined widths only
  // (biperiodic has no wall).
  json confined = json::array();
  for (const json& w : widths)
    if (w.is_number()) confined.push_back(w);
  if (frictions.size() > 1)
    groups.push_back({{"shape", {"sphere"}},
                      {"small_fraction", {0.0}},
                      {"width", confined},
                      {"wall_friction", frictions},
                      {"replicas", replicas},
                      {"backend", backends}});
  // Monodisperse pinacoids.
  if (pinacoids)
    groups.push_back({{"shape", {"pinacoid"}},
                      {"small_fraction", {0.0}},
                      {"width", widths},
                      {"wall_friction", {0.0}},
                      {"replicas", replicas},
                      {"backend", backends}});
  return groups;
}

// A sweep file of the study: the box L_x x W x h (biperiodic period `biperiodic`), the compaction
// settings that differ from the defaults, and the groups.
json studySweep(std::string_view name, std::string_view description, double lengthX, double height,
                const json& compaction, double biperiodic, json groups) {
  json base = {{"box", {{"length_x", lengthX}, {"height", height}}}};
  if (!compaction.empty()) base["compaction"] = compaction;
  return {{"format", kSweepFormat},     {"version", kSweepVersion}, {"name", name},
          {"description", description}, {"base", std::move(base)},  {"biperiodic_width", biperiodic},
          {"groups", std::move(groups)}};
}

}  // namespace

json reproductionSweep(std::string_view scale) {
  if (scale == "paper") {
    // The paper's sizes: L_x = 20 d_L, h = 16 d_L, biperiodic period 20 d_L; the study in full.
    return studySweep(
        "paper", "the confinement study at the paper's sizes", 20.0, 16.0, json::object(), 20.0,
        studyGroups({5.0, 10.0, 20.0, "biperiodic"}, {0.0, 10.0, 25.0, 40.0}, {0.0, 0.3, 0.5, 1.0}, 3, true));
  }
  if (scale == "medium") {
    // Between quick and paper: the paper's families, widths and seeds in a smaller box,
    // L_x = 12 d_L, h = 12 d_L (biperiodic period 12): about 830 (spheres, W = 5) to 4,300
    // (pinacoids, W = 20) grains a monodisperse run, and a bulk region (3 d_L from the floor and
    // from the free surface) about 6 d_L thick, some 410 grains at W = 5. A box that would hold
    // more than 5,000 grains is shortened along x to hold 5,000 (deposition.grain_cap): the small
    // grains of x_S = 40 would make 12,500 at W = 20 (L_x then 4.8), and a run's cost grows faster
    // than its grain count (docs/performance.md, "What sets a medium run's cost").
    // The piles fall on the adaptive step until they are all but at rest (mean kinetic ratio
    // 1e-8), the fall bounded at 300 t0, and the finisher only ends it (a last rattler, the last
    // balance of forces): the finisher cannot do the creep of a large pile, and the dynamic
    // protocol alone leaves some piles not at rest at 300 t0 (docs/performance.md, "The medium
    // scale: how its piles reach rest"). The finisher stops once a step moves no grain more than
    // 1e-5 d instead of the default 1e-6: still a force imbalance tens of times below the
    // equilibrium bound, and half a pinacoid pile's run time for the same packing (docs/model.md,
    // "Quasi-static compaction").
    // Bullet, which has no finisher, stops at 20 t0 and is reported as not at rest.
    json sweep = studySweep(
        "medium",
        "the confinement study in a 12 x W x 12 box (at most 5,000 grains), meant to run overnight on 2 cores", 12.0,
        12.0,
        {{"time_limit", 20.0},
         {"fall_time_limit", 300.0},
         {"protocol", "quasi-static"},
         {"adaptive_dt", true},
         {"switch_kinetic_ratio", 1e-8},
         {"settle_tolerance", 1e-5}},
        12.0, studyGroups({5.0, 10.0, 20.0, "biperiodic"}, {0.0, 10.0, 25.0, 40.0}, {0.0, 0.3, 0.5, 1.0}, 3, true));
    sweep["base"]["deposition"] = {{"grain_cap", 5000}};
    return sweep;
  }
  if (scale == "quick") {
    // Shrunken box: L_x = 4 d_L, h = 7 d_L (the bulk region, 3 d_L away from the floor and from
    // the free surface, is then about 1 d_L thick: the smallest height with a bulk at all), widths
    // scaled down with it (3, 4.5, 6 and biperiodic 6). Monodisperse and x_S = 10 spheres, mu_w
    // in {0, 0.5}, pinacoids, two replicas (so that every table has a standard deviation and every
    // backend difference an uncertainty): every family and every figure of the report appears.
    // Quasi-static protocol (docs/model.md): nscd falls until the pile has fallen (the mean
    // kinetic ratio below switch_kinetic_ratio), at most 30 t0 (fall_time_limit), then its
    // finisher brings the pile to rest. Pinacoid piles take 17 to 20 t0 to fall; handed over at
    // 8 t0 while still tumbling, three of ten did not reach rest within the finisher's 3,000
    // steps (docs/performance.md, "The quasi-static protocol"). Bullet has no finisher and stops
    // at time_limit, 8 t0 (at 30 t0 its runs were 60 % of the study's cost); the report flags
    // every run that is not at rest.
    return studySweep("quick", "the confinement study shrunk to run in minutes on 2 cores", 4.0, 7.0,
                      {{"time_limit", 8.0}, {"fall_time_limit", 30.0}, {"protocol", "quasi-static"}}, 6.0,
                      studyGroups({3.0, 4.5, 6.0, "biperiodic"}, {0.0, 10.0}, {0.0, 0.5}, 2, true));
  }
  if (scale == "tiny") {
    // Smoke test: monodisperse spheres, W = 3 and 5 and biperiodic 4, one seed, both backends:
    // 6 runs of 100-160 grains, L_x = 4, h = 7 (a thin bulk region exists), 6 t0 of compaction.
    return {{"format", kSweepFormat},
            {"version", kSweepVersion},
            {"name", "tiny"},
            {"description", "smoke test of the whole chain (deposit, both backends, analysis, report)"},
            {"base", {{"box", {{"length_x", 4.0}, {"height", 7.0}}}, {"compaction", {{"time_limit", 6.0}}}}},
            {"biperiodic_width", 4.0},
            {"vary",
             {{"shape", {"sphere"}},
              {"small_fraction", {0.0}},
              {"width", {3.0, 5.0, "biperiodic"}},
              {"wall_friction", {0.0}},
              {"seed", {1}},
              {"backend", {"nscd", "bullet"}}}}};
  }
  throw std::invalid_argument(fmt::format("--scale: expected tiny, quick, medium or paper (got '{}')", scale));
}

}  // namespace confpack::study
