#pragma once
// Bit-for-bit equality of doubles, Eigen vectors and quaternions (NaN == NaN, -0.0 != 0.0), for
// the tests that require a result to be reproduced exactly.
#include <cstring>

#include "core/types.hpp"

namespace confpack::testing {

inline bool sameBits(double x, double y) {
  return std::memcmp(&x, &y, sizeof x) == 0;
}

template <class V>
inline bool sameBits(const V& x, const V& y) {
  for (int k = 0; k < x.size(); ++k)
    if (!sameBits(x[k], y[k])) return false;
  return true;
}

inline bool sameBits(const core::Quat& x, const core::Quat& y) {
  return sameBits(x.coeffs(), y.coeffs());
}

}  // namespace confpack::testing
