#pragma once
// The study as the report's sections see it (the parts of study/report.cpp share it; nothing else
// does): its runs grouped by configuration and side, the compared setting's value (the backend
// unless --compare names another, study/report_compare.hpp), the names the page gives families and
// series, the published values of --reference as the sections show them, and the replicas'
// standard errors.
#include <fmt/format.h>

#include <algorithm>
#include <compare>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "study/reference_values.hpp"
#include "study/report.hpp"
#include "study/report_compare.hpp"
#include "study/sweep.hpp"

namespace confpack::study {

/// Standard error of a replica mean, std / sqrt(n); none below two replicas.
std::optional<double> knownStandardError(const ReplicaStat& st);

/// The same as a fit's weight or a figure's error bar: 0 below two replicas (no weight, no bar).
double standardError(const ReplicaStat& st);

// ---------------------------------------------------------------------------------------------
// Configurations and grouping

// A value of a setting the study varies beyond the named axes (a sweep's setting axis, study/
// sweep.hpp), as it names and orders configurations: numbers in numeric order (45 before 100),
// other values by their text. The name is the setting's short name, for the labels only.
struct SettingValue {
  std::string name;
  std::string text;
  std::optional<double> number;

  std::weak_ordering operator<=>(const SettingValue& o) const {
    if (number && o.number)
      return *number < *o.number   ? std::weak_ordering::less
             : *number > *o.number ? std::weak_ordering::greater
                                   : std::weak_ordering::equivalent;
    if (number.has_value() != o.number.has_value())
      return number ? std::weak_ordering::less : std::weak_ordering::greater;
    return text <=> o.text;
  }
  bool operator==(const SettingValue& o) const { return (*this <=> o) == 0; }
};

struct ConfKey {
  int shape = 0;
  double xs = 0.0;
  double mu = 0.0;
  std::vector<SettingValue> settings;  // of the study's varied settings, in their order
  bool periodic = false;
  double width = 0.0;
  auto operator<=>(const ConfKey&) const = default;
};

// Series of a geometrical-model fit: everything but the width.
struct SeriesKey {
  int shape = 0;
  double xs = 0.0;
  double mu = 0.0;
  std::vector<SettingValue> settings;
  auto operator<=>(const SeriesKey&) const = default;
};

SeriesKey seriesOf(const ConfKey& k);

// "Backend" of "backend": a name at the start of a sentence.
std::string capitalized(std::string name);

std::string familyOf(int shape, double xs);

// " alpha_deg=45 E=0.5" (sep "=") or ", alpha_deg = 45, E = 0.5" (sep " = ", lead ", ").
std::string settingsText(const std::vector<SettingValue>& settings, const char* lead = " ", const char* sep = "=");

std::string widthText(const ConfKey& k);

std::string seriesText(const SeriesKey& s);

// A family as the summary and the verdict name it: "MSP: spheres x_S = 0, mu_w = 0".
std::string familyName(const SeriesKey& s);

// The published values of --reference as the sections show them: found per series, each citation
// numbered [1], [2], ... in the order the page first uses it, so the summary's footnotes and the
// figures' legends agree.
class References {
 public:
  explicit References(const std::optional<ReferenceValues>& values) : values_(values ? &*values : nullptr) {}

  bool given() const { return values_ != nullptr; }
  const ReferenceValues& values() const { return *values_; }

  const ReferenceValue* find(const SeriesKey& s, const std::string& key) const {
    return values_ ? values_->find(familyOf(s.shape, s.xs), s.xs, s.mu, key) : nullptr;
  }
  int number(const std::string& citation) {
    const auto it = std::find(citations_.begin(), citations_.end(), citation);
    if (it != citations_.end()) return static_cast<int>(it - citations_.begin()) + 1;
    citations_.push_back(citation);
    return static_cast<int>(citations_.size());
  }
  // "0.64 ± 0.01 [1]"
  std::string cell(const ReferenceValue& v) {
    return fmt::format("{:.4g} ± {:.2g} [{}]", v.value, v.uncertainty, number(v.citation));
  }
  const std::vector<std::string>& citations() const { return citations_; }

 private:
  const ReferenceValues* values_;
  std::vector<std::string> citations_;
};

// Mean +- std (n): 4 significant digits for the mean, 2 for the spread.
std::string statText(const ReplicaStat& s);

// ---------------------------------------------------------------------------------------------
// The study as the sections see it: its runs grouped by configuration and side, the compared
// setting's value (the backend unless --compare names another, study/report_compare.hpp).

class StudyView {
 public:
  // With `tablesFrom` (ReportOptions::tablesFrom), the values of that tables/ folder stand in for
  // each configuration and side of the run table without a finished run here (standIns).
  StudyView(const std::filesystem::path& sweepDir, const std::string& compareKey,
            const std::filesystem::path& tablesFrom = {});
  StudyView(const StudyView&) = delete;  // groups point into records
  StudyView& operator=(const StudyView&) = delete;

  std::filesystem::path runDir(const RunRecord& r) const { return sweepDir / "runs" / r.run.name; }
  bool pair() const { return sides.size() >= 2; }
  const std::string& sideOf(const RunRecord& r) const {
    return recordSides[static_cast<std::size_t>(&r - records.data())];
  }

  // Replica statistics of one quantity over the finished runs of (configuration, side), or its
  // stand-in's when that side has none here.
  ReplicaStat statOf(const ConfKey& k, const std::string& side, const std::string& key) const;

  // The one sample of series `sk` that a per-family quantity is read from for every side, so that
  // the sides are compared at the same configuration: among the configurations with a value of
  // `key` for the most sides, the biperiodic one, else the widest confined one; null when none has
  // a value. A side without a value there has none for the family.
  const ConfKey* sampleOf(const SeriesKey& sk, const std::string& key) const;

  // A key that is null in every run (nematic order of spheres) does not apply to this study.
  bool applies(const std::string& key) const;

  std::set<SeriesKey> seriesKeys() const;

  // The configurations of series `sk` whose values of `side` stand in from --tables-from.
  std::size_t standInCount(const SeriesKey& sk, const std::string& side) const;

  std::filesystem::path sweepDir;
  SweepSpec spec;
  std::vector<RunRecord> records;
  ComparedSetting compared;               // the backends unless --compare names another setting
  std::vector<std::string> recordSides;   // each record's side, as compared.sideOf
  std::vector<std::string> sides;         // the compared values in table order (then a settled series)
  std::vector<std::string> runSettings;   // varied beyond the named axes, as the runs' labels show them
  std::vector<std::string> settings;      // of those, the families': configuration paths (familySettings)
  std::vector<std::string> settingNames;  // their short names
  std::map<ConfKey, std::map<std::string, std::vector<const RunRecord*>>> groups;
  std::set<std::string> keys;      // every quantity of a finished run
  std::set<std::string> csvNames;  // every profile file of a finished run
  // (configuration, side) without a finished run -> key -> the --tables-from folder's statistics
  std::map<std::pair<ConfKey, std::string>, std::map<std::string, ReplicaStat>> standIns;
};

bool unequilibrated(const RunRecord& r);

// A folder's own name (its last path component, "." and ".." resolved).
std::string folderName(const std::filesystem::path& dir);

// The sweep folder's own name, folderName of its path.
std::string sweepName(const StudyView& study);

}  // namespace confpack::study
