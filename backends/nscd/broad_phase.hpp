#pragma once
// Broad phase of the nscd backend: the shared cell list (collision/cell_list.hpp) rebuilt every
// step, with cells of twice the largest grain reach. Each candidate pair comes out once, a < b,
// together with the periodic image of b that is close to a.
#include <cstdint>
#include <vector>

#include "backends/nscd/thread_choice.hpp"
#include "collision/cell_list.hpp"
#include "core/box.hpp"

namespace confpack::nscd {

/// A pair whose bounding spheres (enlarged by the alert distance) overlap. b's image that touches
/// a sits at position_b + shiftX * L_x e_x + shiftY * W e_y.
struct CandidatePair {
  int a = 0;
  int b = 0;
  std::int8_t shiftX = 0;
  std::int8_t shiftY = 0;
};

class BroadPhase {
 public:
  /// Fewer grains than this per thread and the search runs on fewer threads: a parallel region
  /// costs more than it shares below it. Only the speed depends on it, never the output.
  static constexpr int kMinGrainsPerThread = 256;

  /// `maxReach` is the largest interaction radius any grain will have [d_L]; it sets the cell size
  /// 2 maxReach. Throws std::invalid_argument if a periodic length is shorter than two cells,
  /// where the minimum image would no longer be the only image in reach. `threads` > 1 searches
  /// contiguous ranges of first grains on up to that many OpenMP threads (a ThreadChoice times
  /// the team against one thread and keeps the faster); the output of findPairs is the same,
  /// bit for bit, for any thread count.
  BroadPhase(const core::BoxDef& box, double maxReach, int threads = 1);

  /// Fills `out` (cleared first) with every pair i < j such that |minimumImage(x_j - x_i)| <
  /// reach_i + reach_j, sorted by (a, b). Positions need not be wrapped. No allocation once the
  /// buffers have grown.
  void findPairs(const std::vector<core::Vec3>& positions, const std::vector<double>& reach,
                 std::vector<CandidatePair>& out);

 private:
  collision::CellList cells_;
  int threads_ = 1;
  ThreadChoice choice_;
  std::vector<double> slotReach_;                        // reach in the cell list's slot order
  std::vector<std::vector<CandidatePair>> threadPairs_;  // pairs of threads 1.. (thread 0 writes `out`)
};

}  // namespace confpack::nscd
