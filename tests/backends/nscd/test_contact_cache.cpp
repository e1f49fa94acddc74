// The nscd contact cache (backends/nscd/contact_cache.hpp): the warm start's impulses found by
// key.
#include <catch2/catch.hpp>
#include <vector>

#include "backends/nscd/contact_cache.hpp"
#include "core/random.hpp"

using namespace confpack;
using core::Vec3;

TEST_CASE("nscd contact cache: entries given in any order are found by key, from any cursor", "[nscd]") {
  // Keys as the narrow phase makes them: grain pairs in key order, then wall contacts grain by
  // grain (floor -1 before side walls -2, -3: not key order), plus a shuffled variant.
  core::Rng rng(3, core::StreamId::DepositionXY);
  std::vector<nscd::CachedContact> pairs, walls;
  for (int a = 0; a < 200; ++a) {
    for (int b = a + 1; b < 200; ++b)
      if (rng.uniform(0.0, 1.0) < 0.03) pairs.push_back({{a, b, 0, 0, 0u}, 1, {rng.uniform(0.0, 1.0)}, {}, {}});
    for (int w : {-1, -2, -3})
      if (rng.uniform(0.0, 1.0) < 0.1) walls.push_back({{a, w, 0, 0, 0u}, 1, {rng.uniform(0.0, 1.0)}, {}, {}});
  }
  std::vector<nscd::CachedContact> all = pairs;
  all.insert(all.end(), walls.begin(), walls.end());
  const bool shuffled = GENERATE(false, true);
  std::vector<nscd::CachedContact> given = all;
  if (shuffled)
    for (std::size_t i = given.size() - 1; i > 0; --i) std::swap(given[i], given[rng.below(i + 1)]);
  nscd::ContactCache cache;
  std::vector<nscd::CachedContact> buffer = given;
  cache.replace(buffer, 1e-3);
  CHECK(buffer.empty());
  REQUIRE(cache.size() == all.size());
  // Look every key up in the given order (the warm start's), with one cursor, then in reverse.
  std::size_t cursor = 0, found = 0;
  for (const auto& order : {given, std::vector<nscd::CachedContact>(given.rbegin(), given.rend())})
    for (const nscd::CachedContact& e : order) {
      const nscd::CachedContact* hit = cache.find(e.key, cursor);
      REQUIRE(hit != nullptr);
      found += hit->key == e.key && hit->normal[0] == e.normal[0];
      CHECK(hit == cache.find(e.key));
    }
  CHECK(found == 2 * all.size());
  // Absent keys: a pair that is not there, a grain beyond the last, from either end.
  for (std::size_t start : {std::size_t{0}, all.size()}) {
    cursor = start;
    CHECK(cache.find({0, 0, 0, 0, 0u}, cursor) == nullptr);
    CHECK(cache.find({500, 501, 0, 0, 0u}, cursor) == nullptr);
  }
}
