#include "core/input_document.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>

#include "core/json_input.hpp"

namespace confpack::core {

using nlohmann::json;

void refuseInput(std::string_view source, std::string_view field, std::string_view what) {
  throw std::invalid_argument(fmt::format("{}: {}: {}", source, field, what));
}

void refuseUnknownKey(std::string_view source, std::string_view path, std::string_view key, std::string_view known) {
  const std::string name = textExcerpt(key);
  refuseInput(source, path.empty() ? name : fmt::format("{}.{}", path, name),
              fmt::format("unknown key (known: {})", known));
}

std::string keyList(const json& object) {
  std::string keys;
  for (const auto& [key, value] : object.items()) keys += fmt::format("{}{}", keys.empty() ? "" : ", ", key);
  return keys;
}

ObjectReader::ObjectReader(const json& j, std::string_view source, std::string path)
    : j_(j), source_(source), path_(std::move(path)) {
  if (!j_.is_object())
    refuseInput(source_, path_.empty() ? "document" : path_,
                fmt::format("must be a JSON object (got {})", j_.type_name()));
}

void ObjectReader::onlyKeys(std::initializer_list<std::string_view> known) const {
  for (const auto& [key, value] : j_.items()) {
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    std::string list;
    for (std::string_view k : known) list += fmt::format("{}{}", list.empty() ? "" : ", ", k);
    refuseUnknownKey(source_, path_, key, list);
  }
}

void ObjectReader::checkHeader(const DocumentHeader& header) const {
  const json format(header.format);
  if (!has("format")) {
    if (header.formatKey == HeaderKey::Required) refuse("format", fmt::format("missing (expected {})", format.dump()));
  } else if (at("format") != format) {
    refuse("format", fmt::format("must be {} (got {})", format.dump(), jsonExcerpt(at("format"))));
  }
  // Compared as JSON numbers: 1.0 is version 1.
  if (!has("version")) {
    if (header.versionKey == HeaderKey::Required)
      refuse("version", fmt::format("missing (expected {})", header.version));
  } else if (at("version") != json(header.version)) {
    refuse("version", fmt::format("must be {}, the version this build reads (got {})", header.version,
                                  jsonExcerpt(at("version"))));
  }
}

std::string ObjectReader::field(std::string_view key) const {
  return path_.empty() ? std::string(key) : fmt::format("{}.{}", path_, key);
}

const json& ObjectReader::at(std::string_view key, std::string_view why) const {
  if (!has(key)) refuse(key, why.empty() ? std::string("missing") : fmt::format("missing ({})", why));
  return j_.at(std::string(key));
}

double ObjectReader::number(std::string_view key, const Range& range) const {
  const double x = number(key);
  if (!range.contains(x)) refuse(key, fmt::format("must be {} (got {})", range.text(), numberText(x)));
  return x;
}

int ObjectReader::integer(std::string_view key) const {
  const json& v = at(key);
  if (!v.is_number_integer()) refuse(key, fmt::format("must be an integer (got {})", jsonExcerpt(v)));
  // An unsigned value is compared as one: above 2^63 - 1 it would wrap as an int64 (2^64 - 1 to
  // -1, the floor's id).
  constexpr std::int64_t kLimit = 1000000000;
  const bool inRange = v.is_number_unsigned() ? v.get<std::uint64_t>() <= std::uint64_t{kLimit}
                                              : v.get<std::int64_t>() >= -kLimit && v.get<std::int64_t>() <= kLimit;
  if (!inRange) refuse(key, fmt::format("out of range (got {})", v.dump()));
  return static_cast<int>(v.get<std::int64_t>());
}

bool ObjectReader::boolean(std::string_view key) const {
  const json& v = at(key);
  if (!v.is_boolean()) refuse(key, fmt::format("must be true or false (got {})", jsonExcerpt(v)));
  return v.get<bool>();
}

std::string ObjectReader::string(std::string_view key) const {
  const json& v = at(key);
  if (!v.is_string()) refuse(key, fmt::format("must be a string (got {})", jsonExcerpt(v)));
  return v.get<std::string>();
}

const json& ObjectReader::object(std::string_view key) const {
  const json& v = at(key);
  if (!v.is_object()) refuse(key, fmt::format("must be a JSON object (got {})", v.type_name()));
  return v;
}

const json& ObjectReader::array(std::string_view key) const {
  const json& v = at(key);
  if (!v.is_array()) refuse(key, fmt::format("must be an array (got {})", v.type_name()));
  return v;
}

double ObjectReader::toNumber(const json& v, std::string_view field) const {
  if (!v.is_number() || !std::isfinite(v.get<double>()))
    refuseInput(source_, field, fmt::format("must be a finite number (got {})", jsonExcerpt(v)));
  return v.get<double>();
}

void ObjectReader::refuse(std::string_view key, std::string_view what) const {
  refuseInput(source_, field(key), what);
}

ObjectReader readDocument(const json& doc, std::string_view source, const DocumentHeader& header,
                          std::initializer_list<std::string_view> known) {
  ObjectReader top(doc, source);
  top.checkHeader(header);
  top.onlyKeys(known);
  return top;
}

}  // namespace confpack::core
