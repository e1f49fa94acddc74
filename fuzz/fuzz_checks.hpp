#pragma once
// What every fuzz target asserts beyond "no crash, no sanitizer report": a reader refuses bad
// input with std::invalid_argument only (any other exception escapes the target, and libFuzzer
// reports it), with a message that stays short whatever the input holds (a 10 MB key or a deeply
// nested value is not echoed in full), and accepts only what it can write back and read again.
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string_view>

namespace confpack::fuzz {

/// Longest refusal message accepted [characters]: the longest legitimate ones list the allowed
/// keys of a settings table (about 500 characters).
inline constexpr std::size_t kMaxMessageLength = 1500;

/// Stops the run as a crash (libFuzzer then saves the input) when `ok` is false.
inline void require(bool ok, std::string_view what, std::string_view detail = {}) {
  if (ok) return;
  std::fprintf(stderr, "fuzz check failed: %.*s\n%.*s\n", static_cast<int>(what.size()), what.data(),
               static_cast<int>(detail.size()), detail.data());
  std::abort();
}

/// A refusal: one message, not too long, that starts with `source` when it is given.
inline void checkRefusal(const std::invalid_argument& e, std::string_view source = {}) {
  const std::string_view message = e.what();
  require(message.size() <= kMaxMessageLength, "the refusal message is too long", message.substr(0, 300));
  require(source.empty() || message.starts_with(source), "the refusal message does not name the input", message);
}

}  // namespace confpack::fuzz
