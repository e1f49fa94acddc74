#include "core/json_input.hpp"

#include <fmt/format.h>

#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace confpack::core {

using nlohmann::json;

namespace {
// Where the parser stopped, as a field path ("grains[0].size"): the text is parsed again with a
// callback that follows the containers, up to the value nlohmann could not read (its out_of_range
// error carries no position). Only after such a failure, so a good document is parsed once.
std::string failurePath(std::string_view text) {
  struct Level {
    bool array;
    std::string key;
    long index = -1;
  };
  std::vector<Level> levels;
  auto elementStarts = [&] {
    if (!levels.empty() && levels.back().array) ++levels.back().index;
  };
  try {
    [[maybe_unused]] const json kept =
        json::parse(text.begin(), text.end(), [&](int, json::parse_event_t event, json& parsed) {
          switch (event) {
            case json::parse_event_t::object_start:
            case json::parse_event_t::array_start:
              elementStarts();
              levels.push_back({event == json::parse_event_t::array_start, {}});
              break;
            case json::parse_event_t::object_end:
            case json::parse_event_t::array_end:
              if (!levels.empty()) levels.pop_back();
              break;
            case json::parse_event_t::key:
              if (!levels.empty()) levels.back().key = parsed.get<std::string>();
              break;
            case json::parse_event_t::value:
              elementStarts();
              break;
          }
          return true;  // a discarded container would hide its values' events
        });
  } catch (const json::exception&) {
  }
  // An outer array's index counts the container being read; the innermost array's, the elements
  // read before the one that failed.
  // Deep nesting or long keys: the path is cut like any echoed input.
  constexpr std::size_t kPathLimit = 120;
  std::string path;
  for (std::size_t i = 0; i < levels.size() && path.size() <= kPathLimit; ++i) {
    if (levels[i].array)
      path += fmt::format("[{}]", levels[i].index + (i + 1 == levels.size() ? 1 : 0));
    else
      path += fmt::format("{}{}", path.empty() ? "" : ".", textExcerpt(levels[i].key));
  }
  return textExcerpt(path, kPathLimit);
}
}  // namespace

json parseJsonText(std::string_view text, std::string_view source) {
  // nlohmann's message quotes the token it last read, which can be the rest of the file (an
  // unterminated string, a run of bad bytes): cut.
  constexpr std::size_t kMessageLimit = 240;
  try {
    return json::parse(text.begin(), text.end());
  } catch (const json::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}: not valid JSON: {}", source, textExcerpt(e.what(), kMessageLimit)));
  } catch (const json::out_of_range& e) {  // a number beyond a double, e.g. 1e400
    const std::string path = failurePath(text);
    throw std::invalid_argument(fmt::format("{}: {}a number out of the range of a double: {}", source,
                                            path.empty() ? "" : path + ": ", textExcerpt(e.what(), kMessageLimit)));
  }
}

json readJsonFile(const std::filesystem::path& path, std::string_view what) {
  const std::string source = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw std::invalid_argument(fmt::format("{}: is a folder, not a {}", source, what));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(fmt::format("{}: cannot open the {}", source, what));
  std::string text;
  // Not `text << in.rdbuf()`: that insertion catches an exception (std::bad_alloc while the text
  // grows) and only sets failbit, so a file read under memory pressure came out cut short and
  // was refused as invalid JSON instead of failing as out of memory.
  if (const std::uintmax_t size = std::filesystem::file_size(path, ec); !ec) text.reserve(size);
  text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::invalid_argument(fmt::format("{}: cannot read the {}", source, what));
  return parseJsonText(text, source);
}

namespace {
// Appends `v` as JSON text until `out` holds more than `limit` characters. Every level adds at
// least one character, so the recursion stops after `limit` levels at most.
void appendExcerpt(std::string& out, const json& v, std::size_t limit) {
  if (out.size() > limit) return;
  if (v.is_array() || v.is_object()) {
    out += v.is_array() ? '[' : '{';
    bool first = true;
    for (auto it = v.begin(); it != v.end() && out.size() <= limit; ++it) {
      if (!first) out += ',';
      first = false;
      if (v.is_object()) out += json(it.key()).dump() + ':';
      appendExcerpt(out, it.value(), limit);
    }
    out += v.is_array() ? ']' : '}';
  } else {
    out += v.dump();
  }
}
}  // namespace

std::string jsonExcerpt(const json& value, std::size_t limit) {
  std::string out;
  appendExcerpt(out, value, limit);
  return textExcerpt(out, limit);
}

std::string textExcerpt(std::string_view text, std::size_t limit) {
  if (text.size() <= limit) return std::string(text);
  // Not inside a UTF-8 sequence: the message may end up in a JSON file (failed.json), whose
  // writer refuses invalid UTF-8.
  std::size_t cut = limit;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return std::string(text.substr(0, cut)) + "...";
}

}  // namespace confpack::core
