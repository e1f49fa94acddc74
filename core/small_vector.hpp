#pragma once
// A vector whose first N elements live inside the object. The narrow phase builds many tiny
// arrays per pair and per step (8 vertices, 4 contact points, a clip polygon); with std::vector
// every one was a heap allocation. Here nothing is allocated until an array outgrows N, which
// for pinacoids never happens, and any other convex shape still works (it spills to the heap).
#include <algorithm>
#include <array>
#include <cstddef>
#include <initializer_list>
#include <type_traits>
#include <utility>
#include <vector>

namespace confpack::core {

/// Contiguous sequence with inline storage for N elements, spilling to the heap beyond N.
/// The element order and values are those of the std::vector it replaces; only the storage
/// differs. Iterators are pointers (invalidated by any growth).
template <class T, std::size_t N>
class SmallVector {
 public:
  using value_type = T;
  using size_type = std::size_t;
  using iterator = T*;
  using const_iterator = const T*;

  SmallVector() = default;
  SmallVector(std::initializer_list<T> init) { assign(init.begin(), init.end()); }
  SmallVector(const SmallVector& o) { assign(o.begin(), o.end()); }
  SmallVector(SmallVector&& o) noexcept(std::is_nothrow_move_constructible_v<T>) { moveFrom(o); }
  SmallVector& operator=(const SmallVector& o) {
    if (this != &o) assign(o.begin(), o.end());
    return *this;
  }
  SmallVector& operator=(SmallVector&& o) noexcept(std::is_nothrow_move_constructible_v<T>) {
    if (this != &o) moveFrom(o);
    return *this;
  }
  SmallVector& operator=(std::initializer_list<T> init) {
    assign(init.begin(), init.end());
    return *this;
  }

  T* data() { return onHeap_ ? heap_.data() : inline_.data(); }
  const T* data() const { return onHeap_ ? heap_.data() : inline_.data(); }
  size_type size() const { return onHeap_ ? heap_.size() : size_; }
  bool empty() const { return size() == 0; }
  T* begin() { return data(); }
  T* end() { return data() + size(); }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size(); }
  T& operator[](size_type i) { return data()[i]; }
  const T& operator[](size_type i) const { return data()[i]; }
  T& front() { return data()[0]; }
  const T& front() const { return data()[0]; }
  T& back() { return data()[size() - 1]; }
  const T& back() const { return data()[size() - 1]; }

  /// Empties the sequence; heap capacity, if any was needed, is kept for the next fill.
  void clear() {
    size_ = 0;
    heap_.clear();
    onHeap_ = false;
  }

  void push_back(const T& x) { emplace_back(x); }
  template <class... Args>
  T& emplace_back(Args&&... args) {
    if (!onHeap_ && size_ < N) {
      inline_[size_] = T(std::forward<Args>(args)...);
      return inline_[size_++];
    }
    if (!onHeap_) spill();
    return heap_.emplace_back(std::forward<Args>(args)...);
  }

  /// New elements (when growing) are value-initialised, as std::vector::resize does.
  void resize(size_type n) {
    if (!onHeap_ && n <= N) {
      for (size_type i = size_; i < n; ++i) inline_[i] = T();
      size_ = n;
      return;
    }
    if (!onHeap_) spill();
    heap_.resize(n);
  }

  /// Element-wise equality, as for std::vector.
  friend bool operator==(const SmallVector& l, const SmallVector& r) {
    return l.size() == r.size() && std::equal(l.begin(), l.end(), r.begin());
  }

  template <class It>
  void assign(It first, It last) {
    clear();
    for (; first != last; ++first) push_back(*first);
  }

 private:
  // Moves the inline elements to the heap; from now on heap_ holds everything.
  void spill() {
    heap_.reserve(2 * N);
    heap_.assign(inline_.begin(), inline_.begin() + size_);
    size_ = 0;
    onHeap_ = true;
  }
  void moveFrom(SmallVector& o) {
    clear();
    if (o.onHeap_) {
      heap_ = std::move(o.heap_);
      onHeap_ = true;
    } else {
      std::move(o.inline_.begin(), o.inline_.begin() + o.size_, inline_.begin());
      size_ = o.size_;
    }
    o.clear();
  }

  std::array<T, N> inline_;  // live elements [0, size_) while !onHeap_
  size_type size_ = 0;
  bool onHeap_ = false;
  std::vector<T> heap_;  // all elements once onHeap_
};

}  // namespace confpack::core
