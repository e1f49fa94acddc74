#include "backends/nscd/contact_cache.hpp"

#include <algorithm>
#include <stdexcept>

namespace confpack::nscd {

namespace {

bool keyLess(const CachedContact& l, const CachedContact& r) {
  return l.key < r.key;
}
bool keyBefore(const CachedContact& c, const ContactKey& k) {
  return c.key < k;
}

}  // namespace

const CachedContact* ContactCache::find(const ContactKey& key, std::size_t& cursor) const {
  const std::size_t n = entries_.size();
  std::size_t lo = 0, hi = n;
  if (cursor < n && entries_[cursor].key < key) {
    // The key lies ahead of the cursor: exponential search forward, then bisection of the last
    // stretch. entries_[cursor + bound / 2] < key <= entries_[cursor + bound] (or the end).
    std::size_t bound = 1;
    while (cursor + bound < n && entries_[cursor + bound].key < key) bound *= 2;
    lo = cursor + bound / 2 + 1;
    hi = std::min(n, cursor + bound + 1);
  }
  const auto first = entries_.begin();
  const auto it = std::lower_bound(first + static_cast<std::ptrdiff_t>(lo), first + static_cast<std::ptrdiff_t>(hi),
                                   key, keyBefore);
  cursor = static_cast<std::size_t>(it - first);
  return it != entries_.end() && it->key == key ? &*it : nullptr;
}

const CachedContact* ContactCache::find(const ContactKey& key) const {
  std::size_t cursor = entries_.size();
  return find(key, cursor);
}

void ContactCache::replace(std::vector<CachedContact>& entries, double dt) {
  // Entries arrive in contact order: grain pairs sorted by key (the broad phase's order), then the
  // wall contacts grain by grain (a few percent). The sorted head is kept, the rest sorted alone,
  // and the two merged into the old buffer, in linear time for the head; sorting everything
  // (large entries, moved n log n times) was 6% of an 8,000-sphere run. Any order is handled.
  const auto head = std::is_sorted_until(entries.begin(), entries.end(), keyLess);
  std::sort(head, entries.end(), keyLess);
  entries_.resize(entries.size());
  std::merge(entries.begin(), head, head, entries.end(), entries_.begin(), keyLess);
  entries.clear();
  dt_ = dt;
}

nlohmann::json ContactCache::toJson() const {
  nlohmann::json entries = nlohmann::json::array();
  for (const CachedContact& c : entries_) {
    const auto points = [&](const std::array<double, kMaxContactPoints>& a) {
      return nlohmann::json(std::vector<double>(a.begin(), a.begin() + c.pointCount));
    };
    entries.push_back({c.key.a, c.key.b, c.key.shiftX, c.key.shiftY, c.key.feature, points(c.normal),
                       points(c.tangent1), points(c.tangent2)});
  }
  return {{"dt", dt_}, {"entries", std::move(entries)}};
}

void ContactCache::fromJson(const nlohmann::json& j, int grains) {
  const auto bad = [] { return std::invalid_argument("checkpoint: the contact cache is not one this build wrote"); };
  if (!j.is_object() || !j.contains("dt") || !j["dt"].is_number() || !j.contains("entries") || !j["entries"].is_array())
    throw bad();
  std::vector<CachedContact> entries;
  entries.reserve(j["entries"].size());
  for (const nlohmann::json& e : j["entries"]) {
    if (!e.is_array() || e.size() != 8) throw bad();
    for (int k = 0; k < 5; ++k)
      if (!e[k].is_number_integer()) throw bad();
    CachedContact c;
    c.key = {e[0].get<int>(), e[1].get<int>(), static_cast<std::int8_t>(e[2].get<int>()),
             static_cast<std::int8_t>(e[3].get<int>()), e[4].get<std::uint32_t>()};
    if (c.key.a < 0 || c.key.a >= grains || c.key.b < static_cast<int>(core::WallId::SideHigh) || c.key.b >= grains)
      throw bad();
    if (!e[5].is_array() || e[5].size() > static_cast<std::size_t>(kMaxContactPoints)) throw bad();
    const std::size_t count = e[5].size();
    c.pointCount = static_cast<int>(count);
    for (int k = 5; k < 8; ++k) {
      if (!e[k].is_array() || e[k].size() != count) throw bad();
      std::array<double, kMaxContactPoints>& to = k == 5 ? c.normal : k == 6 ? c.tangent1 : c.tangent2;
      for (std::size_t p = 0; p < count; ++p) {
        if (!e[k][p].is_number()) throw bad();
        to[p] = e[k][p].get<double>();
      }
    }
    entries.push_back(c);
  }
  replace(entries, j["dt"].get<double>());
}

}  // namespace confpack::nscd
