#include "study/reference_values.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/input_document.hpp"
#include "core/json_input.hpp"
#include "core/settings_table.hpp"

namespace confpack::study {

using core::refuseInput;
using nlohmann::json;

const std::vector<ReferenceQuantity>& referenceQuantities() {
  static const std::vector<ReferenceQuantity> q = {{"phi_bulk", "phi_bulk"},
                                                   {"C", "C"},
                                                   {"Z_bulk", "Z_bulk"},
                                                   {"C_Z", "C_Z"},
                                                   {"lambda_L_over_d_avg", "lambda_L/d_avg"}};
  return q;
}

const std::vector<std::string>& referenceFamilies() {
  static const std::vector<std::string> f = {"MSP", "BSP", "MPP", "BPP"};
  return f;
}

namespace {

// One published number, read through a settings table named after its place in the file, so that
// its messages say "families.MSP.phi_bulk.uncertainty: must be >= 0 (got -1)".
core::SettingsTable<ReferenceValue> valueTable(const std::string& where) {
  using R = ReferenceValue;
  core::SettingsTable<R> t(where);
  t.number("value", &R::value, core::Range::any(), "the quantity's", "the published value")
      .number("uncertainty", &R::uncertainty, core::Range::atLeast(0.0), "the quantity's",
              "its uncertainty as published (0 for an exact value such as the isostatic Z = 6)")
      .text("citation", &R::citation, "where it is published");
  return t;
}

ReferenceValue readValue(const json& j, const std::string& where, std::string_view source) {
  const auto table = valueTable(where);
  ReferenceValue v;
  try {
    table.read(j, v);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("{}: {}", source, e.what()));
  }
  // A number without its uncertainty or its source cannot be weighed against a study's.
  for (const auto& f : table.fields())
    if (!j.contains(f.key))
      refuseInput(source, where + "." + f.key, "missing (a reference value needs value, uncertainty and citation)");
  return v;
}

std::string quantityKeys() {
  std::string s;
  for (const ReferenceQuantity& q : referenceQuantities()) s += (s.empty() ? "" : ", ") + q.key;
  return s;
}

// x_S (in [0, 100], and 0 exactly when the family is monodisperse) or mu_w (>= 0), given `field`.
void readSelector(const std::string& key, const json& v, const std::string& field, std::string_view source,
                  ReferenceEntry& out) {
  if (key == "x_S") {
    if (!v.is_number() || !(v.get<double>() >= 0.0 && v.get<double>() <= 100.0))
      refuseInput(source, field, fmt::format("must be a number in [0, 100] (got {})", core::jsonExcerpt(v, 40)));
    // The family's letter and x_S say the same thing: they must not contradict each other.
    const bool bidisperse = out.family[0] == 'B';
    if (bidisperse && v.get<double>() == 0.0)
      refuseInput(source, field, fmt::format("{} is bidisperse: x_S must be > 0 (got 0)", out.family));
    if (!bidisperse && v.get<double>() != 0.0)
      refuseInput(source, field,
                  fmt::format("{} is monodisperse: x_S must be 0 (got {})", out.family, core::jsonExcerpt(v, 40)));
    out.smallFraction = v.get<double>();
  } else {
    if (!v.is_number() || !(v.get<double>() >= 0.0) || !std::isfinite(v.get<double>()))
      refuseInput(source, field, fmt::format("must be a number >= 0 (got {})", core::jsonExcerpt(v, 40)));
    out.wallFriction = v.get<double>();
  }
}

ReferenceEntry readEntry(const json& e, const std::string& family, const std::string& where, std::string_view source) {
  const core::ObjectReader entry(e, source, where);
  ReferenceEntry out;
  out.family = family;
  out.where = where;
  for (const auto& [key, v] : e.items()) {
    const std::string field = entry.field(core::textExcerpt(key));
    if (key == "x_S" || key == "mu_w")
      readSelector(key, v, field, source, out);
    else if (std::any_of(referenceQuantities().begin(), referenceQuantities().end(),
                         [&](const ReferenceQuantity& q) { return q.key == key; }))
      out.values[key] = readValue(v, field, source);
    else
      core::refuseUnknownKey(source, where, key, "x_S, mu_w, " + quantityKeys());
  }
  if (out.values.empty())
    refuseInput(source, where, fmt::format("gives no value (known quantities: {})", quantityKeys()));
  return out;
}

// How specific an entry is: x_S and mu_w given first, a family-wide entry last.
int specificity(const ReferenceEntry& e) {
  return (e.smallFraction ? 2 : 0) + (e.wallFriction ? 1 : 0);
}

}  // namespace

const ReferenceValue* ReferenceValues::find(std::string_view family, double smallFraction, double wallFriction,
                                            std::string_view key) const {
  const ReferenceValue* best = nullptr;
  int bestSpecificity = -1;
  for (const ReferenceEntry& e : entries) {
    if (e.family != family) continue;
    if (e.smallFraction && *e.smallFraction != smallFraction) continue;
    if (e.wallFriction && *e.wallFriction != wallFriction) continue;
    const auto it = e.values.find(std::string(key));
    if (it == e.values.end() || specificity(e) <= bestSpecificity) continue;
    best = &it->second;
    bestSpecificity = specificity(e);
  }
  return best;
}

namespace {

// The entries of one family: an object, or a non-empty list of them.
void readFamily(const std::string& family, const json& v, std::string_view source, ReferenceValues& out) {
  const std::string where = "families." + core::textExcerpt(family);
  const auto& known = referenceFamilies();
  if (std::find(known.begin(), known.end(), family) == known.end())
    refuseInput(source, where, "unknown family (known: MSP, BSP, MPP, BPP)");
  if (!v.is_array()) {
    out.entries.push_back(readEntry(v, family, where, source));
    return;
  }
  if (v.empty()) refuseInput(source, where, "expected a non-empty list of entries");
  for (std::size_t i = 0; i < v.size(); ++i)
    out.entries.push_back(readEntry(v[i], family, fmt::format("{}[{}]", where, i), source));
}

// Two entries that match the same series and give the same quantity would leave the report to
// pick one of two published numbers silently.
void refuseDuplicates(const ReferenceValues& values, std::string_view source) {
  for (std::size_t i = 0; i < values.entries.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      const ReferenceEntry& a = values.entries[i];
      const ReferenceEntry& b = values.entries[j];
      if (a.family != b.family || a.smallFraction != b.smallFraction || a.wallFriction != b.wallFriction) continue;
      for (const auto& [key, _] : a.values)
        if (b.values.count(key))
          refuseInput(source, a.where + "." + key,
                      fmt::format("given twice for the same family, x_S and mu_w (also in {})", b.where));
    }
}

}  // namespace

ReferenceValues parseReferenceValues(const json& doc, std::string_view source) {
  const core::ObjectReader top = core::readDocument(
      doc, source, {kReferenceFormat, kReferenceVersion, core::HeaderKey::Optional, core::HeaderKey::Optional},
      {"format", "version", "description", "families"});
  ReferenceValues out;
  out.source = std::string(source);
  if (top.has("description")) out.description = top.string("description");
  const json& families = top.at("families", "an object keyed by MSP, BSP, MPP, BPP");
  if (!families.is_object() || families.empty())
    top.refuse("families", "expected a non-empty object keyed by MSP, BSP, MPP, BPP");
  for (const auto& [family, v] : families.items()) readFamily(family, v, source, out);
  refuseDuplicates(out, source);
  return out;
}

ReferenceValues readReferenceValues(const std::filesystem::path& path) {
  return parseReferenceValues(core::readJsonFile(path, "reference file"), path.string());
}

}  // namespace confpack::study
