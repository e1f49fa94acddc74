// The report's verdict, the two sides compared (study/report_verdict.hpp).
#include "study/report_verdict.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace confpack::study {

namespace {

// What the finished runs of (series, backend) say of their contact networks' rigidity
// (docs/model.md, "Isostaticity"), as a sentence of the verdict: how many carry self-stresses,
// whether any lies between grains rather than through the floor and walls, and the share of free
// motions (mechanisms k / n_dof). Empty when none has the block (frictional walls, results from
// before the block existed).
std::string rigiditySentence(const StudyView& study, const SeriesKey& sk, const std::string& side) {
  int runs = 0, stressed = 0, stressedBetweenGrains = 0;
  double perConstraint = 0.0, freeShare = 0.0;
  for (const auto& [k, bySide] : study.groups) {
    if (seriesOf(k) != sk || !bySide.count(side)) continue;
    for (const RunRecord* r : bySide.at(side)) {
      if (r->status != RunStatus::Done) continue;
      const auto value = [&](const char* key) {
        const auto it = r->values.find(key);
        return it == r->values.end() ? std::optional<double>() : it->second;
      };
      const auto h = value("rigidity/self_stresses"), hGrains = value("rigidity/self_stresses_between_grains"),
                 m = value("rigidity/constraints"), k3 = value("rigidity/mechanisms"),
                 dof = value("rigidity/degrees_of_freedom");
      if (!h || !hGrains || !m || !k3 || !dof || !(*dof > 0.0)) continue;
      ++runs;
      stressed += *h > 0.0;
      stressedBetweenGrains += *hGrains > 0.0;
      perConstraint += *m > 0.0 ? *h / *m : 0.0;
      freeShare += *k3 / *dof;
    }
  }
  if (runs == 0) return "";
  const std::string free = fmt::format("{:.2g} % of their motions free (mechanisms, mean)", 100.0 * freeShare / runs);
  if (stressed == 0)
    return fmt::format(" {}'s {} packing{}: no self-stress (the geometry fixes the contact forces), {}.", side, runs,
                       runs == 1 ? "" : "s", free);
  return fmt::format(" {}'s {} packings: {} with self-stresses, {:.2g} per constraint (mean), {}; {}.", side, runs,
                     stressed, perConstraint / runs,
                     stressedBetweenGrains == 0
                         ? std::string("all through the floor or the walls, none between grains alone")
                         : fmt::format("{} with some between grains", stressedBetweenGrains),
                     free);
}

// nscd against Bullet (the first two backends) for every family and summary quantity.
// Two estimates of one quantity compared: their difference, its combined standard error (both
// errors needed: one side's alone would judge the other side's number exact), and whether they
// differ by more than twice it.
struct Comparison {
  double diff = 0.0;
  double se = 0.0;  ///< 0: unknown
  bool bothErrors = false;
  bool known() const { return se > 0.0; }
  bool differ() const { return known() && std::abs(diff) > 2.0 * se; }
  std::string verdict() const {
    return known() ? (differ() ? "yes: differ (*)" : "no: agree") : diff == 0.0 ? "no: identical" : "no standard error";
  }
};

Comparison compare(const Estimate& a, const Estimate& b) {
  Comparison c;
  c.diff = a.value - b.value;
  c.bothErrors = a.error && b.error;
  c.se = c.bothErrors ? std::hypot(*a.error, *b.error) : 0.0;
  return c;
}

// What a difference between two backends is made of, once the second's piles were brought to rest
// by the first (a sweep's settle_with): one that vanishes was the second stopping before rest.
std::string differenceMadeOf(const Comparison& stopped, const Comparison& settled) {
  if (!stopped.known() || !settled.known()) return "-";
  if (stopped.differ() && !settled.differ()) return "not at rest";
  if (stopped.differ() && settled.differ()) return "the solvers' own";
  if (!stopped.differ() && settled.differ()) return "appears at rest";
  return "none";
}

// The sentences of one backend's runs of a family: equilibrium, rigidity, failed and missing runs.
std::string runsText(const StudyView& study, const StudySummary& summary, const SeriesKey& sk,
                     const std::string& side) {
  std::string text;
  const auto found = summary.runs.find({sk, side});
  if (found == summary.runs.end()) return text;
  const RunCount& n = found->second;
  if (n.done > 0 && n.equilibrated == 0)
    text += fmt::format(" None of {}'s {} finished runs reached equilibrium: this compares unequilibrated piles.", side,
                        n.done);
  else if (n.unequilibrated > 0)
    text += fmt::format(
        " {} of {}'s {} finished runs did not reach equilibrium: the comparison is partly of "
        "unequilibrated piles.",
        n.unequilibrated, side, n.done);
  text += rigiditySentence(study, sk, side);
  // Failed runs said apart from missing ones, which a study still running has many of.
  const std::size_t missing = n.total - n.done - n.failed;
  const auto are = [](std::size_t k) { return k == 1 ? "is" : "are"; };
  if (n.failed > 0 && missing > 0)
    text += fmt::format(" {} of {}'s {} runs did not finish: {} failed, {} {} missing (not run or interrupted).",
                        n.total - n.done, side, n.total, n.failed, missing, are(missing));
  else if (n.failed > 0)
    text += fmt::format(" {} of {}'s {} runs failed.", n.failed, side, n.total);
  else if (missing > 0)
    text +=
        fmt::format(" {} of {}'s {} runs {} missing (not run or interrupted).", missing, side, n.total, are(missing));
  const std::size_t standIns = study.standInCount(sk, side);
  if (standIns > 0)
    text += fmt::format(" {}'s values at {} width{} are another report's tables' (the introduction names them).", side,
                        standIns, standIns == 1 ? "" : "s");
  return text;
}

// The sentence of one quantity compared between backends a and b.
std::string comparisonText(const std::string& a, const std::string& b, const std::string& quantity, const Comparison& c,
                           const std::string& both) {
  if (!c.known() && c.diff == 0.0) return fmt::format(" {} and {} give the same {} {}.", a, b, quantity, both);
  if (!c.known())
    return fmt::format(" {} and {} give {} {} with no standard error to compare them.", a, b, quantity, both);
  if (c.differ())
    return fmt::format(
        " {} and {} differ on {} by {:+.3g} ± {:.2g}, {} standard errors {}.", a, b, quantity, c.diff, c.se,
        std::abs(c.diff) > 100.0 * c.se ? "more than 100" : fmt::format("{:.1f}", std::abs(c.diff) / c.se), both);
  return fmt::format(" {} and {} agree on {} within 2 standard errors {}.", a, b, quantity, both);
}

}  // namespace

void addVerdictSection(Document& doc, const StudyView& study, const StudySummary& summary) {
  doc.heading(2, study.compared.backend() ? std::string("Cross-solver verdict")
                                          : fmt::format("Verdict: {} against {}", study.sides[0], study.sides[1]));
  if (!study.pair()) {
    doc.paragraph("This study ran a single backend: there is nothing to compare.");
    return;
  }
  const std::string& a = study.sides[0];
  const std::string& b = study.sides[1];
  // b's piles brought to rest by a (a sweep's settle_with), when the study has them.
  const std::string settled = settledName(b);
  const bool withSettled = std::find(study.sides.begin(), study.sides.end(), settled) != study.sides.end();
  doc.paragraph(
      fmt::format("{} against {}: the difference {} − {}, its combined standard error sqrt(SE1² + SE2²), "
                  "and whether it is larger than twice that error.",
                  a, b, a, b));
  if (withSettled)
    doc.paragraph(fmt::format(
        "{} is {}'s piles as it stopped them, each taken on to rest by {} (settle_with): the same comparison "
        "against it says what each difference is made of. A difference that vanishes once {}'s piles are at rest "
        "is \"not at rest\" ({} stopped early, or its impulses are not converged forces); one that stays is "
        "\"the solvers' own\", a difference in the packings they make.",
        settled, b, a, b, b));
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> sentences;
  for (const SeriesKey& sk : study.seriesKeys()) {
    std::string text;
    for (const SummaryQuantity& q : summary.quantities) {
      const auto ea = q.values.find({sk, a});
      const auto eb = q.values.find({sk, b});
      if (ea == q.values.end() || eb == q.values.end()) continue;
      const Comparison c = compare(ea->second, eb->second);
      std::vector<std::string> row = {familyName(sk),
                                      q.name,
                                      ea->second.text,
                                      eb->second.text,
                                      fmt::format("{:+.3g}", c.diff),
                                      c.bothErrors ? fmt::format("{:.2g}", c.se) : "-",
                                      c.verdict()};
      text += comparisonText(a, b, q.name, c, fmt::format("({} against {})", ea->second.text, eb->second.text));
      if (withSettled) {
        const auto es = q.values.find({sk, settled});
        if (es == q.values.end()) {
          row.insert(row.end(), {"-", "-", "-", "-", "-"});
        } else {
          const Comparison cs = compare(ea->second, es->second);
          const std::string madeOf = differenceMadeOf(c, cs);
          row.insert(row.end(), {es->second.text, fmt::format("{:+.3g}", cs.diff),
                                 cs.bothErrors ? fmt::format("{:.2g}", cs.se) : "-", cs.verdict(), madeOf});
          text +=
              comparisonText(a, settled, q.name, cs, fmt::format("({} against {})", ea->second.text, es->second.text));
          if (madeOf != "-" && madeOf != "none") text += fmt::format(" On {}: {}.", q.name, madeOf);
        }
      }
      rows.push_back(std::move(row));
    }
    for (const std::string& side : {a, b}) text += runsText(study, summary, sk, side);
    if (withSettled) text += runsText(study, summary, sk, settled);
    if (!text.empty()) sentences.push_back(fmt::format("For {}:{}", familyName(sk), text));
  }
  std::vector<std::string> header = {"family", "quantity", a, b, a + " − " + b, "combined SE", "|diff| > 2 SE"};
  if (withSettled)
    header.insert(header.end(), {settled, a + " − " + settled, "combined SE", "|diff| > 2 SE", "the difference is"});
  doc.table(header, rows);
  if (!sentences.empty()) doc.bullets(sentences);
}

}  // namespace confpack::study
