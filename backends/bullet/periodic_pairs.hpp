#pragma once
// Pairs of grains that touch across a periodic face (docs/model.md, "Bullet:
// sequential impulses"). Bullet has no periodic
// boundaries: its broad phase sees the grains where they are, so it finds every pair whose two
// grains touch inside the box, and this finder supplies the others: grain a touching the image
// of grain b displaced by a whole number of periods. No Bullet types here, so it is testable and
// reusable on its own.
#include <vector>

#include "core/box.hpp"

namespace confpack::bullet {

/// Grain a touches (within the reach) the image of grain b at position_b + shift.
struct ImagePair {
  int a = 0;  ///< a < b
  int b = 0;
  int shiftX = 0;  ///< shift = (shiftX L_x, shiftY W, 0)
  int shiftY = 0;
  core::Vec3 shift = core::Vec3::Zero();  ///< [d_L]
};

/// Finds image pairs among grains wrapped into the box. Only grains within `reach` of a periodic
/// face can have one, so only those go into the shared cell list (collision/cell_list.hpp),
/// whose region query returns every periodic image near a grain: in short boxes, where one grain
/// can touch two images of another, each of them.
class PeriodicPairFinder {
 public:
  /// `reach` is the largest centre distance at which two grains can interact: twice the largest
  /// bounding radius plus the contact threshold [d_L]. Throws std::invalid_argument if a
  /// periodic length is shorter than the reach (a grain would touch its own image).
  PeriodicPairFinder(const core::BoxDef& box, double reach);

  /// Pairs (a < b, non-zero shift) whose bounding spheres, radius[i] plus `threshold`, overlap
  /// across a periodic face, in a deterministic order (a, then b, then shift).
  std::vector<ImagePair> find(const std::vector<core::Vec3>& positions, const std::vector<double>& radii,
                              double threshold) const;

 private:
  core::BoxDef box_;
  double reach_ = 0.0;
};

}  // namespace confpack::bullet
