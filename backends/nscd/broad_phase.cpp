#include "backends/nscd/broad_phase.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace confpack::nscd {

using core::Vec3;

namespace {

// The cell side 2 maxReach, checked first: the cell list's own message would not name nscd.
double cellSide(double maxReach) {
  if (!(maxReach > 0.0)) throw std::invalid_argument("nscd broad phase: grain reach must be positive");
  return 2.0 * maxReach;
}

}  // namespace

BroadPhase::BroadPhase(const core::BoxDef& box, double maxReach, int threads)
    : cells_(box, cellSide(maxReach)), threads_(std::max(1, threads)), choice_(threads) {
  const double cell = 2.0 * maxReach;
  // The minimum-image convention is exact only if no grain can touch two images of another one.
  if (box.lengthX < 2.0 * cell)
    throw std::invalid_argument(
        fmt::format("nscd: box length_x {} is too short for grains of interaction diameter {} (need >= {})",
                    box.lengthX, cell, 2.0 * cell));
  if (box.periodicY && box.width < 2.0 * cell)
    throw std::invalid_argument(
        fmt::format("nscd: periodic width {} is too short for grains of interaction diameter {} (need >= {})",
                    box.width, cell, 2.0 * cell));
}

void BroadPhase::findPairs(const std::vector<Vec3>& positions, const std::vector<double>& reach,
                           std::vector<CandidatePair>& out) {
  out.clear();
  const int n = static_cast<int>(positions.size());
  if (n == 0) return;
  cells_.build(positions);
  // The second grain's reach in slot order, read contiguously with its position.
  cells_.toSlotOrder(std::span<const double>(reach), slotReach_);
  // Raw pointers and values, captured by copy: nothing the push_back below calls can change them.
  const double* reachById = reach.data();
  const double* slotReach = slotReach_.data();
  const double lx = cells_.box().lengthX, w = cells_.box().width;
  const bool periodicY = cells_.box().periodicY;
  auto keepTouching = [=](std::vector<CandidatePair>& o, int i, int j, int slot, Vec3 d, Vec3 raw) {
    const double r = reachById[i] + slotReach[slot];
    if (d.squaredNorm() >= r * r) return;
    CandidatePair pair;
    pair.a = i;
    pair.b = j;
    pair.shiftX = static_cast<std::int8_t>(std::lround((d.x() - raw.x()) / lx));
    pair.shiftY = periodicY ? static_cast<std::int8_t>(std::lround((d.y() - raw.y()) / w)) : 0;
    o.push_back(pair);
  };
  // The search is ~all of the broad phase's time; on a team when the grains are many enough
  // and the ThreadChoice found the team faster.
  const int useful = std::min(threads_, std::max(1, n / kMinGrainsPerThread));
  if (useful > 1) {
    const auto start = std::chrono::steady_clock::now();
    const int team = choice_.next() > 1 ? useful : 1;
    cells_.findPairs<&CandidatePair::b>(keepTouching, out, team, threadPairs_);
    choice_.record(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return;
  }
  cells_.findPairs<&CandidatePair::b>(keepTouching, out);
}

}  // namespace confpack::nscd
