#pragma once
// The confinement study (docs/model.md, "The study and its report") at four scales, as sweep
// files, for `confpack reproduce`:
//   spheres with x_S in {0, 10, 25, 40} and monodisperse pinacoids, W in {5, 10, 20} and
//   biperiodic, mu_w in {0, 0.3, 0.5, 1} for monodisperse spheres, 3 seeds, both backends.
// - paper: the paper's sizes (L_x = 20 d_L, h = 16 d_L, biperiodic period 20 d_L), the full
//   study above (174 runs). Hours to days on a workstation: meant for a cluster (docs/sweeps.md).
// - medium: the paper's families, widths and seeds in a 12 x W x 12 box, at most 5,000 grains a
//   run, nscd piles brought to rest (its results and cost: docs/medium.md).
// - quick: the same families in a shrunken box and fewer combinations, so that it finishes in
//   under 20 minutes on 2 cores (see the note in docs/sweeps.md for the measured time).
// - tiny:  a smoke test of the whole chain (deposit, both backends, analysis, report), a few
//   small piles of spheres; under 3 minutes on 2 cores.
#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "study/sweep.hpp"

namespace confpack::study {

/// Names accepted by reproductionSweep, in order: tiny, quick, medium, paper.
const std::vector<std::string_view>& reproductionScales();

/// The sweep file (JSON document, the same format as `confpack sweep` reads) of a scale.
/// Throws std::invalid_argument for an unknown scale.
nlohmann::json reproductionSweep(std::string_view scale);

}  // namespace confpack::study
