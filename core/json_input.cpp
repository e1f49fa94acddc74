#include "core/json_input.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "core/interrupt.hpp"

namespace confpack::core {

using nlohmann::json;

namespace {
const char* fileKind(mode_t mode) {
  if (S_ISFIFO(mode)) return "FIFO";
  if (S_ISCHR(mode)) return "character device";
  if (S_ISBLK(mode)) return "block device";
  if (S_ISSOCK(mode)) return "socket";
  return "special file";
}

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

namespace {
// nlohmann's own document builder, polling for SIGINT and SIGTERM every 65,536 containers (a
// packing file of 2 GiB takes about a minute to parse). Not json::parse's callback form: it takes
// 2.7 times as long (a 70 MB document: 6.4 s against 2.3 s).
class PollingDomParser : public nlohmann::detail::json_sax_dom_parser<json> {
 public:
  PollingDomParser(json& result, std::string_view source) : json_sax_dom_parser(result), source_(source) {}
  bool start_object(std::size_t n) {
    poll();
    return json_sax_dom_parser::start_object(n);
  }
  bool start_array(std::size_t n) {
    poll();
    return json_sax_dom_parser::start_array(n);
  }

 private:
  void poll() {
    if ((++containers_ & 0xFFFF) == 0) stopIfRequested([&] { return fmt::format("while reading {}", source_); });
  }
  std::string_view source_;
  std::size_t containers_ = 0;
};
}  // namespace

json parseJsonText(std::string_view text, std::string_view source) {
  // nlohmann's message quotes the token it last read, which can be the rest of the file (an
  // unterminated string, a run of bad bytes): cut.
  constexpr std::size_t kMessageLimit = 240;
  try {
    json result;
    PollingDomParser parser(result, source);
    json::sax_parse(text.begin(), text.end(), &parser);
    return result;
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
  // Non-blocking, so that opening a FIFO with no writer returns at once instead of waiting for
  // one; what the descriptor is (fstat) is checked before a byte is read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    if (errno == EISDIR) throw std::invalid_argument(fmt::format("{}: is a folder, not a {}", source, what));
    throw std::invalid_argument(fmt::format("{}: cannot open the {} ({})", source, what, std::strerror(errno)));
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    throw std::invalid_argument(fmt::format("{}: cannot read the {} ({})", source, what, std::strerror(errno)));
  if (S_ISDIR(st.st_mode)) throw std::invalid_argument(fmt::format("{}: is a folder, not a {}", source, what));
  if (!S_ISREG(st.st_mode))
    throw std::invalid_argument(
        fmt::format("{}: is a {}, not a regular file: give the {} itself", source, fileKind(st.st_mode), what));
  const auto size = static_cast<std::uintmax_t>(st.st_size);
  if (size > kMaxJsonFileBytes)
    throw std::invalid_argument(
        fmt::format("{}: {} bytes, more than the {} bytes a {} may have", source, size, kMaxJsonFileBytes, what));
  // Not `text << in.rdbuf()` or a stream at all: a stream's insertion catches std::bad_alloc and
  // only sets failbit, so a file read under memory pressure came out cut short and was refused as
  // invalid JSON instead of failing as out of memory. Read to the end rather than to st_size (a
  // file may grow meanwhile, or, in /proc, have no size), the bound checked as it goes.
  constexpr std::size_t kChunk = std::size_t{1} << 16;
  std::string text;
  text.reserve(static_cast<std::size_t>(size) + kChunk);
  std::size_t got = 0;
  for (;;) {
    if (text.size() < got + kChunk) text.resize(got + kChunk);
    stopIfRequested([&] { return fmt::format("while reading {}", source); });
    const ssize_t n = ::read(fd, text.data() + got, kChunk);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::invalid_argument(fmt::format("{}: cannot read the {} ({})", source, what, std::strerror(errno)));
    }
    got += static_cast<std::size_t>(n);
    if (got > kMaxJsonFileBytes)
      throw std::invalid_argument(
          fmt::format("{}: more than the {} bytes a {} may have", source, kMaxJsonFileBytes, what));
  }
  text.resize(got);
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
