#pragma once
// One reader for the JSON documents a user gives (a packing file, a sweep file, a run table, a
// reference file): their header, known keys and typed fields checked by the same code, so that a
// file of another kind, a misspelt key or a value of the wrong type is refused alike in each, as
// "SOURCE: FIELD: WHAT" ("packing.json: grains[3].size: must be a finite number (got null)").
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "core/settings_table.hpp"

namespace confpack::core {

/// Refuses input: throws std::invalid_argument "SOURCE: FIELD: WHAT".
[[noreturn]] void refuseInput(std::string_view source, std::string_view field, std::string_view what);

/// Refuses `key` of the object at `path` ("" for the document itself): "SOURCE: PATH.KEY: unknown
/// key (known: KNOWN)", the key cut to an excerpt. `known` is the list as shown ("a, b, c").
[[noreturn]] void refuseUnknownKey(std::string_view source, std::string_view path, std::string_view key,
                                   std::string_view known);

/// The keys of a JSON object as a message lists them: "a, b, c".
std::string keyList(const nlohmann::json& object);

/// Whether a header key may be absent: a file confpack writes states it, a hand-written one may
/// leave it out (and is checked when it gives it).
enum class HeaderKey { Required, Optional };

/// What a document's "format" and "version" keys must say.
struct DocumentHeader {
  std::string_view format;  ///< "confpack-packing"
  int version = 1;          ///< the one version this build reads
  HeaderKey formatKey = HeaderKey::Required;
  HeaderKey versionKey = HeaderKey::Required;
};

/// One JSON object of a document at a path ("grains[3]"; "" for the document itself), whose
/// fields are read by type. The object must outlive the reader; `source` is copied.
class ObjectReader {
 public:
  /// Refuses a value that is not an object: "SOURCE: PATH: must be a JSON object (got TYPE)",
  /// PATH "document" for the document itself.
  ObjectReader(const nlohmann::json& j, std::string_view source, std::string path = {});

  /// Refuses a key outside `known` (a typo must not silently drop data): refuseUnknownKey.
  void onlyKeys(std::initializer_list<std::string_view> known) const;
  /// Refuses a document of another kind or version: "format: missing (expected "F")", "format:
  /// must be "F" (got ...)", "version: missing (expected V)", "version: must be V (got ...)".
  void checkHeader(const DocumentHeader& header) const;

  bool has(std::string_view key) const { return j_.contains(key); }
  /// "PATH.KEY" (KEY alone at the top), as messages name the field.
  std::string field(std::string_view key) const;
  /// The value of `key`; refuses its absence: "missing", or "missing (WHY)" when `why` is given.
  const nlohmann::json& at(std::string_view key, std::string_view why = {}) const;

  double number(std::string_view key) const { return toNumber(at(key), field(key)); }
  /// A finite number inside `range`: "must be RANGE (got V)" otherwise.
  double number(std::string_view key, const Range& range) const;
  /// An integer within +-1e9 (an index, an id): "out of range (got I)" beyond.
  int integer(std::string_view key) const;
  bool boolean(std::string_view key) const;
  std::string string(std::string_view key) const;
  const nlohmann::json& object(std::string_view key) const;
  const nlohmann::json& array(std::string_view key) const;
  /// `v` (an element, named `field` in full) as a finite number: "must be a finite number (got
  /// V)" otherwise; a null usually is a non-finite number written (JSON has no spelling for it).
  double toNumber(const nlohmann::json& v, std::string_view field) const;

  /// Refuses the value of `key`: "SOURCE: PATH.KEY: WHAT".
  [[noreturn]] void refuse(std::string_view key, std::string_view what) const;
  std::string_view source() const { return source_; }
  const std::string& path() const { return path_; }

 private:
  const nlohmann::json& j_;
  std::string source_;  // owned: a reader may outlive the string it was given (file.string())
  std::string path_;
};

/// The top of a document: an object whose header says `header`'s kind and version (checked
/// first, so that a file of another kind is told so rather than its keys), and whose keys are
/// among `known` (the header's included).
ObjectReader readDocument(const nlohmann::json& doc, std::string_view source, const DocumentHeader& header,
                          std::initializer_list<std::string_view> known);

}  // namespace confpack::core
