#pragma once
// The packing file reader as the packing targets feed it: the fuzzer's bytes as packing.json.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "fuzz/fuzz_checks.hpp"

namespace confpack::fuzz {

inline constexpr std::string_view kPackingSource = "packing.json";

/// The packing the reader accepts from `data`, or nullopt when it refused them (checked as a
/// refusal: std::invalid_argument, a short message naming the file).
inline std::optional<core::Packing> acceptedPacking(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    return core::packingFromJson(core::parseJsonText(text, kPackingSource), kPackingSource);
  } catch (const std::invalid_argument& e) {
    checkRefusal(e, kPackingSource);
    return std::nullopt;
  }
}

}  // namespace confpack::fuzz
