#pragma once
// FNV-1a (64 bit) over bytes: the fingerprint of the fixed-seed regression tests. A recorded
// constant changes only in a commit that says why.
#include <cstdint>
#include <cstring>
#include <string_view>

namespace confpack::testing {

struct Fnv1a {
  std::uint64_t value = 1469598103934665603ull;

  void mix(std::string_view bytes) {
    for (unsigned char c : bytes) value = (value ^ c) * 1099511628211ull;
  }
  /// The bytes of v in memory order.
  void mix(double v) {
    char bytes[sizeof v];
    std::memcpy(bytes, &v, sizeof v);
    mix(std::string_view(bytes, sizeof bytes));
  }
};

}  // namespace confpack::testing
