#include "core/random.hpp"

#include <cmath>
#include <numbers>

namespace confpack::core {

namespace {
std::uint64_t splitmix64(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
std::uint64_t rotl(std::uint64_t x, int k) {
  return (x << k) | (x >> (64 - k));
}
}  // namespace

Rng::Rng(std::uint64_t seed, StreamId stream, std::uint64_t runIndex) {
  // Mix the three identifiers through SplitMix64 one after the other so that nearby seeds,
  // streams and runs give unrelated states.
  std::uint64_t x = seed;
  std::uint64_t h = splitmix64(x);
  x = h ^ static_cast<std::uint64_t>(stream);
  h = splitmix64(x);
  x = h ^ runIndex;
  for (auto& s : s_) s = splitmix64(x);
}

std::uint64_t Rng::next() {
  // xoshiro256** (Blackman & Vigna 2018).
  const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

std::uint64_t Rng::below(std::uint64_t n) {
  // Lemire's rejection keeps the draw unbiased.
  const std::uint64_t threshold = (0 - n) % n;
  for (;;) {
    const __uint128_t m = static_cast<__uint128_t>(next()) * n;
    if (static_cast<std::uint64_t>(m) >= threshold) return static_cast<std::uint64_t>(m >> 64);
  }
}

double Rng::normal() {
  if (hasSpare_) {
    hasSpare_ = false;
    return spareNormal_;
  }
  double u1 = uniform();
  while (u1 <= 0.0) u1 = uniform();
  const double u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = 2.0 * std::numbers::pi * u2;
  spareNormal_ = r * std::sin(a);
  hasSpare_ = true;
  return r * std::cos(a);
}

Quat Rng::uniformQuaternion() {
  for (;;) {
    Quat q(normal(), normal(), normal(), normal());
    const double n = q.norm();
    if (n > 1e-12) {
      q.coeffs() /= n;
      return q;
    }
  }
}

}  // namespace confpack::core
