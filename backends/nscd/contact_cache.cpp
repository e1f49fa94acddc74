#include "backends/nscd/contact_cache.hpp"

#include <algorithm>

namespace confpack::nscd {

namespace {

bool keyLess(const CachedContact& l, const CachedContact& r) { return l.key < r.key; }
bool keyBefore(const CachedContact& c, const ContactKey& k) { return c.key < k; }

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
  const auto it =
      std::lower_bound(first + static_cast<std::ptrdiff_t>(lo), first + static_cast<std::ptrdiff_t>(hi), key, keyBefore);
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

}  // namespace confpack::nscd
