#include "backends/nscd/contact_cache.hpp"

#include <algorithm>

namespace confpack::nscd {

const CachedContact* ContactCache::find(const ContactKey& key) const {
  auto it = std::lower_bound(entries_.begin(), entries_.end(), key,
                             [](const CachedContact& c, const ContactKey& k) { return c.key < k; });
  return it != entries_.end() && it->key == key ? &*it : nullptr;
}

void ContactCache::replace(std::vector<CachedContact>& entries, double dt) {
  // Entries arrive in contact order, which is sorted by (a, b) already for grain pairs but not
  // across walls and images; sort fully. Swapping keeps both buffers' capacity alive.
  std::sort(entries.begin(), entries.end(),
            [](const CachedContact& l, const CachedContact& r) { return l.key < r.key; });
  entries_.swap(entries);
  entries.clear();
  dt_ = dt;
}

}  // namespace confpack::nscd
