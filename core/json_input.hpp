#pragma once
// JSON text given by a user (a packing file, a sweep file, a run configuration, --backend-options):
// parsed into a document, with every failure of nlohmann's parser turned into one
// std::invalid_argument that names where the text came from, so that each reader of the toolkit
// refuses bad JSON with the same kind of message and the same exit code (bad input, 2).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace confpack::core {

/// Parses `text`. Throws std::invalid_argument "SOURCE: not valid JSON: ..." for a syntax error
/// and "SOURCE: a number out of the range of a double: ..." for a number such as 1e400.
nlohmann::json parseJsonText(std::string_view text, std::string_view source);

/// Largest JSON file read [bytes]: a packing of a million grains (the largest deposit) with its
/// contacts is well under 1 GiB, and parsing takes several times the file's size in memory.
inline constexpr std::uintmax_t kMaxJsonFileBytes = std::uintmax_t{2} << 30;

/// Reads and parses a JSON file. Only a regular file of at most kMaxJsonFileBytes is read, refused
/// before reading anything otherwise: a folder ("FILE: is a folder, not a WHAT"), a FIFO or a
/// device (/dev/zero, /dev/urandom: endless; a FIFO: may never be written), a file too large, or
/// one that cannot be opened ("FILE: cannot open the WHAT (<reason>)") is refused with
/// std::invalid_argument, as is bad JSON (parseJsonText). Opening never blocks. `what` names the
/// kind of file: "packing file", "sweep file".
nlohmann::json readJsonFile(const std::filesystem::path& path, std::string_view what);

/// `value` as a message shows it: its JSON text when short, else its first `limit` characters
/// followed by "..." (a 10 MB string or a deeply nested array is not echoed in full; the text is
/// written with a budget, never recursing deeper than the budget allows).
std::string jsonExcerpt(const nlohmann::json& value, std::size_t limit = 60);

/// `text` cut to `limit` characters followed by "..." when longer (a key or a name echoed in a
/// message).
std::string textExcerpt(std::string_view text, std::size_t limit = 60);

}  // namespace confpack::core
