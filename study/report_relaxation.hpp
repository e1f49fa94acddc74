#pragma once
// The report's relaxation section (docs/model.md, "Relaxation histories"): how phi of the bulk, Z
// and the largest force ratio moved over a compaction, per family, width and backend, averaged over
// the replicas, so that a reader sees whether a quantity had stopped moving when the runs ended.
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "study/report_document.hpp"
#include "study/report_figures.hpp"

namespace confpack::study {

/// The replicas of one configuration and backend: their result.json timing.history arrays.
struct RelaxationLine {
  std::string label;    ///< "W=10 nscd (n=3)"
  int color = 1;        ///< one per width
  bool dashed = false;  ///< backends after the first
  std::vector<nlohmann::json> histories;
};

/// One family's lines.
struct RelaxationFamily {
  std::string name;  ///< as the summary names it
  std::string stem;  ///< file-name stem of its figures ("relaxation_01")
  std::vector<RelaxationLine> lines;
};

/// The mean over `histories` of the entry `key` ("solid_fraction", "Z", "max_force_ratio") at each
/// time of `times` [t0]: each run's value at t is linear between its checks, its first value
/// before its first check and its last after its end (a run that stopped stays as it stopped;
/// at one time, as after the finisher's steps, which take no simulated time, the last entry
/// counts). Entries whose value is null or not finite are skipped; a time no run has a value
/// at is NaN. `log10` averages log10 of the values (ratios span decades).
std::vector<double> meanHistory(const std::vector<nlohmann::json>& histories, const std::string& key,
                                const std::vector<double>& times, bool log10 = false);

/// The times a family's figures are drawn at: `points` evenly from 0 to the latest end of any
/// of its runs [t0].
std::vector<double> relaxationTimes(const RelaxationFamily& family, int points = 60);

/// Adds the section: a short definition, then per family three figures against t (phi of the
/// bulk, Z, log10 of the largest force ratio). Families without a history are left out; a study
/// with none says so. `side` names what a family's lines compare ("backend", "value of solver").
void addRelaxationSection(Document& doc, FigureWriter& figures, const std::vector<RelaxationFamily>& families,
                          const std::string& side = "backend");

}  // namespace confpack::study
