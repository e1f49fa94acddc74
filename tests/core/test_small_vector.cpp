// SmallVector (core/small_vector.hpp) behaves as a std::vector across its inline capacity: a
// random sequence of operations on both gives the same contents after every step.
#include <algorithm>
#include <catch2/catch.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/small_vector.hpp"

using confpack::core::SmallVector;

namespace {

template <class T, std::size_t N>
bool sameAs(const SmallVector<T, N>& s, const std::vector<T>& v) {
  return s.size() == v.size() && std::equal(s.begin(), s.end(), v.begin()) && s.empty() == v.empty();
}

}  // namespace

TEST_CASE("a SmallVector follows a std::vector through pushes, resizes, clears, copies and moves") {
  // std::string elements: a spill or a move that loses or duplicates an element shows up.
  std::mt19937 rng(5);
  SmallVector<std::string, 4> s;
  std::vector<std::string> v;
  for (int step = 0; step < 4000; ++step) {
    const int op = static_cast<int>(rng() % 8);
    std::string x = std::to_string(rng() % 1000);
    x.insert(0, 1, 'e');  // not "e" + ...: GCC 12 warns wrongly on it (-Wrestrict, GCC bug 105329)
    switch (op) {
      case 0:
      case 1:
      case 2:
        s.push_back(x);
        v.push_back(x);
        break;
      case 3: {
        const std::size_t n = rng() % 10;  // across the inline capacity of 4 both ways
        s.resize(n);
        v.resize(n);
        break;
      }
      case 4:
        if (rng() % 4 == 0) {
          s.clear();
          v.clear();
        }
        break;
      case 5: {
        const SmallVector<std::string, 4> copy(s);
        CHECK(sameAs(copy, v));
        CHECK(copy == s);
        SmallVector<std::string, 4> assigned{"x"};
        assigned = s;
        CHECK(assigned == s);
        break;
      }
      case 6: {
        SmallVector<std::string, 4> moved(std::move(s));
        s = std::move(moved);
        break;
      }
      case 7:
        if (!v.empty()) {
          CHECK(s.front() == v.front());
          CHECK(s.back() == v.back());
          s.back() = x;
          v.back() = x;
        }
        break;
    }
    REQUIRE(sameAs(s, v));
  }
  SmallVector<int, 2> list = {1, 2, 3};
  CHECK(list.size() == 3);
  list = {7};
  CHECK(sameAs(list, std::vector<int>{7}));
}
