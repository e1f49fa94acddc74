#pragma once
// Persistent contact cache for warm starting (after Jolt's contact cache): the
// impulses of the last step, keyed by (grain a, grain b or wall, periodic image of b, feature
// pair). A sorted flat vector searched by bisection: no allocation per step once it has grown,
// and a deterministic iteration order.
#include <array>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "backends/nscd/narrow_phase.hpp"

namespace confpack::nscd {

struct ContactKey {
  int a = 0;
  int b = 0;
  std::int8_t shiftX = 0;
  std::int8_t shiftY = 0;
  std::uint32_t feature = 0;
  auto operator<=>(const ContactKey&) const = default;

  static ContactKey of(const ContactGeometry& c) { return {c.a, c.b, c.shiftX, c.shiftY, c.feature}; }
};

/// Impulses of one contact at the end of a step [impulse = force x dt].
struct CachedContact {
  ContactKey key;
  int pointCount = 0;
  std::array<double, kMaxContactPoints> normal{};
  std::array<double, kMaxContactPoints> tangent1{};
  std::array<double, kMaxContactPoints> tangent2{};
};

class ContactCache {
 public:
  /// The entry of the previous step with this key, or nullptr.
  const CachedContact* find(const ContactKey& key) const;
  /// The same, searching from `cursor` (the position of the last key looked up, updated): keys
  /// looked up in increasing order cost O(1) each instead of a bisection of the whole cache.
  const CachedContact* find(const ContactKey& key, std::size_t& cursor) const;
  /// Time step of the stored impulses [t0] (0 if empty): warm starts scale impulses by dt_new / dt.
  double dt() const { return dt_; }

  /// Replaces the content by `entries` (taken over, left empty) stored with time step dt.
  void replace(std::vector<CachedContact>& entries, double dt);
  std::size_t size() const { return entries_.size(); }

  /// The cache as JSON, for a run's checkpoint: {"dt": ..., "entries": [[a, b, shiftX, shiftY,
  /// feature, [normal], [tangent1], [tangent2]], ...]}, one impulse a point.
  nlohmann::json toJson() const;
  /// Replaces the content by what toJson() wrote; throws std::invalid_argument on anything else
  /// (a grain index outside [0, grains); b may be a core::WallId).
  void fromJson(const nlohmann::json& j, int grains);

 private:
  std::vector<CachedContact> entries_;
  double dt_ = 0.0;
};

}  // namespace confpack::nscd
