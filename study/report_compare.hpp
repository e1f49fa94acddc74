#pragma once
// What a study report puts side by side (docs/sweeps.md, "The report"): by default the backends,
// nscd against Bullet; with `confpack report --compare KEY` the two values of any other setting of
// the run configuration, KEY its path in config.json ("backend_options.solver"). Each value is then
// a series where each backend was one, in the summary, the verdict, the figures and the tables, and
// the families are every other axis, the backend among them where the runs' backends differ.
#include <string>
#include <vector>

#include "study/report.hpp"
#include "study/sweep.hpp"

namespace confpack::study {

/// The setting a report compares, and the words its page names it by.
struct ComparedSetting {
  std::string key = "backend";      ///< path in the run configuration ("backend_options.solver")
  std::string column = "backend";   ///< a table's column: the key's last name ("solver")
  std::string noun = "backend";     ///< in a sentence: "backend", else "value of solver"
  std::string plural = "backends";  ///< "backends", else "values of solver"

  bool backend() const { return key == "backend"; }
  /// Whether a settle (RunRecord::settle, a sweep's settle_with) is a series of the comparison: it
  /// is of the backends' only, where it is the second backend's piles brought to rest by the first.
  bool keepsSettles() const { return backend(); }
  /// The series of a run: its value of `key` as settingText writes it ("nlgs", "1e-08"); a
  /// settle's backend is settledName of its run's (loadStudy).
  std::string sideOf(const SweepRun& run) const;
  /// The paths the families show beside W, shape, x_S, mu_w (variedSettings of the table's runs):
  /// without `key`, and with "backend" where the runs' backends differ and `key` is not it.
  std::vector<std::string> familySettings(const std::vector<SweepRun>& tableRuns) const;
};

/// `--compare KEY` checked against the run table (SweepRun, without settles): every run has a value
/// at KEY that is a setting, not a section, KEY is not one the families are told apart by (W,
/// biperiodic, shape, x_S, mu_w), and the runs have exactly two values of it. Otherwise
/// std::invalid_argument naming KEY and, as it applies, the run without it or the values found.
ComparedSetting compareSetting(const std::string& key, const std::vector<SweepRun>& tableRuns);

}  // namespace confpack::study
