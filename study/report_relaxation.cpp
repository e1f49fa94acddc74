#include "study/report_relaxation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

namespace confpack::study {

namespace {

// One run's (t, value) points of `key`, in time order, the last entry at a repeated time kept.
std::vector<std::pair<double, double>> pointsOf(const nlohmann::json& history, const std::string& key, bool log10) {
  std::vector<std::pair<double, double>> out;
  if (!history.is_array()) return out;
  for (const nlohmann::json& e : history) {
    if (!e.is_object() || !e.contains("time") || !e["time"].is_number() || !e.contains(key) || !e[key].is_number())
      continue;
    const double t = e["time"].get<double>();
    double v = e[key].get<double>();
    if (log10) v = v > 0.0 ? std::log10(v) : std::numeric_limits<double>::quiet_NaN();
    if (!std::isfinite(t) || !std::isfinite(v)) continue;
    if (!out.empty() && t <= out.back().first) {
      if (t == out.back().first) out.back().second = v;
      continue;  // out of order: a hand-edited file
    }
    out.emplace_back(t, v);
  }
  return out;
}

double valueAt(const std::vector<std::pair<double, double>>& p, double t) {
  if (t <= p.front().first) return p.front().second;
  if (t >= p.back().first) return p.back().second;
  const auto hi = std::upper_bound(p.begin(), p.end(), t, [](double x, const auto& q) { return x < q.first; });
  const auto lo = hi - 1;
  const double w = (t - lo->first) / (hi->first - lo->first);
  return lo->second + w * (hi->second - lo->second);
}

struct Quantity {
  const char* key;
  const char* title;
  bool log10;
};

constexpr std::array<Quantity, 3> kQuantities = {{{"solid_fraction", "phi of the bulk", false},
                                                  {"Z", "Z (force-carrying contacts per bulk grain)", false},
                                                  {"max_force_ratio", "log10 of the largest force ratio", true}}};

}  // namespace

std::vector<double> meanHistory(const std::vector<nlohmann::json>& histories, const std::string& key,
                                const std::vector<double>& times, bool log10) {
  std::vector<std::vector<std::pair<double, double>>> runs;
  for (const nlohmann::json& h : histories)
    if (auto p = pointsOf(h, key, log10); !p.empty()) runs.push_back(std::move(p));
  std::vector<double> out;
  out.reserve(times.size());
  for (double t : times) {
    if (runs.empty()) {
      out.push_back(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    double sum = 0.0;
    for (const auto& p : runs) sum += valueAt(p, t);
    out.push_back(sum / static_cast<double>(runs.size()));
  }
  return out;
}

std::vector<double> relaxationTimes(const RelaxationFamily& family, int points) {
  double end = 0.0;
  for (const RelaxationLine& line : family.lines)
    for (const nlohmann::json& h : line.histories)
      if (auto p = pointsOf(h, "max_force_ratio", false); !p.empty()) end = std::max(end, p.back().first);
  std::vector<double> t;
  if (!(end > 0.0) || points < 2) return t;
  for (int i = 0; i < points; ++i) t.push_back(end * i / (points - 1));
  return t;
}

void addRelaxationSection(Document& doc, FigureWriter& figures, const std::vector<RelaxationFamily>& families,
                          const std::string& side) {
  doc.heading(2, "Relaxation histories");
  doc.paragraph(fmt::format(
      "How each pile came to rest: phi of the bulk region, its coordination Z and the largest force ratio of the "
      "equilibrium test at every check of the compaction, against the simulated time t (t0), averaged over the "
      "replicas (a run that ended holds its last value). A quantity still moving at the end of a {}'s lines "
      "was not at rest when its runs stopped. The quasi-static finisher's steps take no simulated time: its "
      "checks stack at the end of the fall. Solid: first {}; dashed: the others.",
      side, side));
  bool any = false;
  for (const RelaxationFamily& family : families) {
    const std::vector<double> times = relaxationTimes(family);
    if (times.empty()) continue;
    for (std::size_t q = 0; q < kQuantities.size(); ++q) {
      Plot p{fmt::format("{}_{}", family.stem, kQuantities[q].key),
             fmt::format("{}: {} against t", family.name, kQuantities[q].title),
             "t (t0)",
             kQuantities[q].title,
             {},
             {},
             true};
      for (const RelaxationLine& line : family.lines) {
        Series s{line.label, line.color, line.dashed, true, {}};
        s.markers = false;
        const std::vector<double> mean = meanHistory(line.histories, kQuantities[q].key, times, kQuantities[q].log10);
        for (std::size_t i = 0; i < times.size(); ++i)
          if (std::isfinite(mean[i])) s.points.push_back({times[i], mean[i], 0.0});
        if (!s.points.empty()) p.series.push_back(std::move(s));
      }
      if (p.series.empty()) continue;
      doc.figure(figures.draw(p));
      any = true;
    }
  }
  if (!any) doc.paragraph("No run of this study recorded a relaxation history.");
}

}  // namespace confpack::study
