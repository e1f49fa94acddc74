#pragma once
// One typed description of a settings struct: each field's JSON key, member, unit, accepted
// values and one-line meaning, declared once. From it come the JSON reading (only known keys,
// each of the right type, in range, named in the error), the JSON writing, the validation of a
// struct built in code, and the Markdown table the docs and `confpack options` show.
//
//   const SettingsTable<NscdSettings>& t = ...;
//   t.number("theta", &NscdSettings::theta, Range::closed(0.5, 1.0), "-", "Moreau-Jean theta");
//
// Messages read "<where>.<key>: must be in [0.5, 1] (got 0.3)", `where` naming the struct as
// the user wrote it ("compaction", "nscd", "bullet").
#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/json_input.hpp"

namespace confpack::core {

/// The finite values a numeric field accepts: an interval whose ends may be open or absent.
struct Range {
  double low = -std::numeric_limits<double>::infinity();
  double high = std::numeric_limits<double>::infinity();
  bool lowOpen = false, highOpen = false;

  static Range closed(double lo, double hi) { return {lo, hi, false, false}; }
  static Range open(double lo, double hi) { return {lo, hi, true, true}; }
  static Range leftOpen(double lo, double hi) { return {lo, hi, true, false}; }  ///< (lo, hi]
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static Range atLeast(double lo) { return {lo, std::numeric_limits<double>::infinity(), false, false}; }
  static Range atMost(double hi) { return {-std::numeric_limits<double>::infinity(), hi, false, false}; }
  static Range any() { return {}; }

  /// Finite and inside (NaN and infinities are never inside).
  bool contains(double v) const;
  /// "in [0.5, 1]", "> 0", ">= 1", "<= 0", "any number".
  std::string text() const;
};

/// Text of a number as messages and tables print it (shortest form, no 300-digit DBL_MAX).
std::string numberText(double v);

template <class T>
class SettingsTable {
 public:
  struct Field {
    std::string key, unit, accepted, help;
    std::function<void(const nlohmann::json&, T&)> read;  ///< type-checked; the range is checked after
    std::function<nlohmann::json(const T&)> write;
    std::function<void(const T&)> validate;  ///< throws with the key named
    bool nested = false;  ///< a section: its keys are checked as it reads them, its rules by validate()
  };

  explicit SettingsTable(std::string where) : where_(std::move(where)) {}

  const std::string& where() const { return where_; }
  const std::vector<Field>& fields() const { return fields_; }
  bool has(const std::string& key) const { return find(key) != nullptr; }

  SettingsTable& number(const char* key, double T::*member, Range range, const char* unit, const char* help) {
    return add(
        key, unit, range.text(), help,
        [w = where_, key, member](const nlohmann::json& j, T& t) { t.*member = asNumber(w, key, j); },
        [member](const T& t) { return nlohmann::json(t.*member); },
        [w = where_, key, member, range](const T& t) { inRange(w, key, t.*member, range); });
  }
  /// A number where JSON null (written for +infinity) means "no limit".
  SettingsTable& numberOrNone(const char* key, double T::*member, Range range, const char* unit, const char* help) {
    return add(
        key, unit, range.text() + ", or null for no limit", help,
        [w = where_, key, member](const nlohmann::json& j, T& t) {
          t.*member = j.is_null() ? std::numeric_limits<double>::infinity() : asNumber(w, key, j);
        },
        [member](const T& t) {
          return std::isinf(t.*member) && t.*member > 0 ? nlohmann::json(nullptr) : nlohmann::json(t.*member);
        },
        [w = where_, key, member, range](const T& t) {
          if (!(std::isinf(t.*member) && t.*member > 0)) inRange(w, key, t.*member, range);
        });
  }
  /// A number where JSON "auto" (held as 0, which `range` must exclude) leaves the value to the
  /// settings' owner. A number is checked as it is read: a 0 in the file is refused, not "auto".
  SettingsTable& numberOrAuto(const char* key, double T::*member, Range range, const char* unit, const char* help) {
    return add(
        key, unit, range.text() + ", or \"auto\"", help,
        [w = where_, key, member, range](const nlohmann::json& j, T& t) {
          if (j == "auto") {
            t.*member = 0.0;
            return;
          }
          if (!j.is_number()) fail(w, key, fmt::format("must be a number or \"auto\" (got {})", jsonExcerpt(j, 40)));
          inRange(w, key, j.get<double>(), range);  // here, so that a number the range refuses is never read as "auto"
          t.*member = j.get<double>();
        },
        [member](const T& t) { return t.*member == 0.0 ? nlohmann::json("auto") : nlohmann::json(t.*member); },
        [w = where_, key, member, range](const T& t) {
          if (t.*member != 0.0) inRange(w, key, t.*member, range);
        });
  }
  template <class Int>
  SettingsTable& integer(const char* key, Int T::*member, Range range, const char* unit, const char* help) {
    return add(
        key, unit, range.text(), help,
        [w = where_, key, member, range](const nlohmann::json& j, T& t) {
          if (!j.is_number_integer()) fail(w, key, fmt::format("must be an integer (got {})", jsonExcerpt(j, 40)));
          const long double v = j.is_number_unsigned() ? static_cast<long double>(j.get<std::uint64_t>())
                                                       : static_cast<long double>(j.get<std::int64_t>());
          if (v < static_cast<long double>(std::numeric_limits<Int>::min()) ||
              v > static_cast<long double>(std::numeric_limits<Int>::max()))
            fail(w, key, fmt::format("must be {} (got {})", range.text(), jsonExcerpt(j, 40)));
          t.*member = static_cast<Int>(v);
        },
        [member](const T& t) { return nlohmann::json(t.*member); },
        [w = where_, key, member, range](const T& t) { inRange(w, key, static_cast<double>(t.*member), range); });
  }
  SettingsTable& flag(const char* key, bool T::*member, const char* help) {
    return add(
        key, "-", "true or false", help,
        [w = where_, key, member](const nlohmann::json& j, T& t) {
          if (!j.is_boolean()) fail(w, key, fmt::format("must be true or false (got {})", jsonExcerpt(j, 40)));
          t.*member = j.get<bool>();
        },
        [member](const T& t) { return nlohmann::json(t.*member); }, [](const T&) {});
  }
  /// Free text that must not be empty (a citation, a name).
  SettingsTable& text(const char* key, std::string T::*member, const char* help) {
    return add(
        key, "-", "a non-empty string", help,
        [w = where_, key, member](const nlohmann::json& j, T& t) {
          if (!j.is_string() || j.get_ref<const std::string&>().empty())
            fail(w, key, fmt::format("must be a non-empty string (got {})", jsonExcerpt(j, 40)));
          t.*member = j.get<std::string>();
        },
        [member](const T& t) { return nlohmann::json(t.*member); }, [](const T&) {});
  }
  /// One of a few names, each standing for a value of E.
  template <class E>
  SettingsTable& choice(const char* key, E T::*member, std::vector<std::pair<std::string, E>> names, const char* help) {
    std::string accepted;
    for (const auto& [name, value] : names) accepted += fmt::format("{}\"{}\"", accepted.empty() ? "" : " or ", name);
    return add(
        key, "-", accepted, help,
        [w = where_, key, member, names, accepted](const nlohmann::json& j, T& t) {
          for (const auto& [name, value] : names)
            if (j == name) {
              t.*member = value;
              return;
            }
          fail(w, key, fmt::format("must be {} (got {})", accepted, jsonExcerpt(j, 40)));
        },
        [member, names](const T& t) {
          for (const auto& [name, value] : names)
            if (t.*member == value) return nlohmann::json(name);
          return nlohmann::json(nullptr);
        },
        [](const T&) {});
  }
  /// A nested settings object with its own table (e.g. the run configuration's "box"): its keys
  /// read over the member's current values (readKeys), written and validated by `table`, whose
  /// `where` names it in messages. `appliesTo`, if given, says when the section is validated
  /// (a pinacoid's shape only in a population of pinacoids).
  template <class S>
  SettingsTable& section(const char* key, S T::*member, const SettingsTable<S>& (*table)(), const char* help,
                         std::function<bool(const T&)> appliesTo = {}) {
    add(
        key, "-", fmt::format("an object (`confpack options {}`)", table().where()), help,
        [member, table](const nlohmann::json& j, T& t) { table().readKeys(j, t.*member); },
        [member, table](const T& t) { return table().write(t.*member); },
        [member, table, appliesTo](const T& t) {
          if (!appliesTo || appliesTo(t)) table().validate(t.*member);
        });
    fields_.back().nested = true;
    return *this;
  }
  /// A field read, written and checked by the caller's own functions (a value no other kind
  /// describes, e.g. a free JSON object); `read` and `validate` throw naming the key.
  SettingsTable& field(const char* key, const char* unit, std::string accepted, const char* help,
                       std::function<void(const nlohmann::json&, T&)> read,
                       std::function<nlohmann::json(const T&)> write, std::function<void(const T&)> validate) {
    return add(key, unit, std::move(accepted), help, std::move(read), std::move(write), std::move(validate));
  }
  /// A rule across fields, checked after the fields' own ranges (e.g. min <= max).
  SettingsTable& rule(std::function<void(const T&)> check) {
    rules_.push_back(std::move(check));
    return *this;
  }

  /// Sets the fields whose keys `j` has (the others keep their values in `t`), then validates.
  /// Throws std::invalid_argument naming the key: not an object, an unknown key (with the list of
  /// known ones), a value of the wrong type or out of range.
  void read(const nlohmann::json& j, T& t) const {
    readKeys(j, t);
    validate(t);
  }
  /// Sets the fields whose keys `j` has, each checked for its type and range, and leaves the
  /// rest, the rules across fields included, to validate(): a document read in parts (a sweep
  /// setting one key at a time) may pass through states its rules refuse.
  void readKeys(const nlohmann::json& j, T& t) const {
    requireObject(j);
    for (const auto& [key, value] : j.items()) readKey(key, value, t);
  }
  /// readKeys() for one key of an object, for a reader that handles some keys itself. The JSON
  /// is never copied: a value may be nested deeper than a recursive copy's stack allows.
  void readKey(const std::string& key, const nlohmann::json& value, T& t) const {
    const Field* f = find(key);
    if (!f) {
      std::string known;
      for (const Field& g : fields_) known += fmt::format("{}{}", known.empty() ? "" : ", ", g.key);
      throw std::invalid_argument(fmt::format("{}.{}: unknown key (known: {})", where_, textExcerpt(key, 40), known));
    }
    f->read(value, t);
    if (!f->nested) f->validate(t);
  }
  void requireObject(const nlohmann::json& j) const {
    if (!j.is_object())
      throw std::invalid_argument(fmt::format("{}: must be a JSON object (got {})", where_, j.type_name()));
  }
  /// Throws "<where>.<key>: missing" for the first of `keys` that `j` (an object) lacks: for
  /// documents that must state a value rather than take its default.
  void require(const nlohmann::json& j, std::initializer_list<const char*> keys) const {
    requireObject(j);
    for (const char* key : keys)
      if (!j.contains(key)) fail(where_, key, "missing");
  }
  nlohmann::json write(const T& t) const {
    nlohmann::json j = nlohmann::json::object();
    for (const Field& f : fields_) j[f.key] = f.write(t);
    return j;
  }
  void validate(const T& t) const {
    for (const Field& f : fields_) f.validate(t);
    for (const auto& r : rules_) r(t);
  }
  /// | key | default | unit | accepted values | meaning |, defaults from `defaults`.
  std::string markdown(const T& defaults) const {
    std::string s = "| key | default | unit | accepted values | meaning |\n|---|---|---|---|---|\n";
    for (const Field& f : fields_)
      s += fmt::format("| `{}` | `{}` | {} | {} | {} |\n", f.key, f.write(defaults).dump(), f.unit, f.accepted, f.help);
    return s;
  }

 private:
  SettingsTable& add(const char* key, const char* unit, std::string accepted, const char* help,
                     std::function<void(const nlohmann::json&, T&)> read, std::function<nlohmann::json(const T&)> write,
                     std::function<void(const T&)> validate) {
    fields_.push_back({key, unit, std::move(accepted), help, std::move(read), std::move(write), std::move(validate)});
    return *this;
  }
  const Field* find(const std::string& key) const {
    for (const Field& f : fields_)
      if (f.key == key) return &f;
    return nullptr;
  }
  // The field readers capture `where` by value, not `this`: a table is returned by value.
  [[noreturn]] static void fail(const std::string& where, const std::string& key, const std::string& what) {
    throw std::invalid_argument(fmt::format("{}.{}: {}", where, key, what));
  }
  static double asNumber(const std::string& w, const char* key, const nlohmann::json& j) {
    if (!j.is_number()) fail(w, key, fmt::format("must be a number (got {})", jsonExcerpt(j, 40)));
    return j.get<double>();
  }
  static void inRange(const std::string& w, const char* key, double v, const Range& range) {
    if (!range.contains(v)) fail(w, key, fmt::format("must be {} (got {})", range.text(), numberText(v)));
  }

  std::string where_;
  std::vector<Field> fields_;
  std::vector<std::function<void(const T&)>> rules_;
};

}  // namespace confpack::core
