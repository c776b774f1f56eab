// StaticVector<T, N>: a vector with compile-time capacity and storage inside the object.
// Never allocates. Full and out-of-range are reported (Status) or asserted (index misuse).
#pragma once

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>

#include "swf/core/assert.hpp"
#include "swf/core/status.hpp"

namespace swf::core {

template <typename T, std::size_t N>
class StaticVector {
  static_assert(N > 0, "capacity must be positive");

 public:
  using value_type = T;
  using iterator = T*;
  using const_iterator = const T*;

  StaticVector() = default;
  StaticVector(const StaticVector& other) { CopyFrom(other); }
  StaticVector& operator=(const StaticVector& other) {
    if (this != &other) {
      clear();
      CopyFrom(other);
    }
    return *this;
  }
  ~StaticVector() { clear(); }

  static constexpr std::size_t capacity() { return N; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == N; }

  // Appends a copy; kFull when there is no room (the vector is unchanged).
  Status push_back(const T& value) { return emplace_back(value); }

  template <typename... Args>
  Status emplace_back(Args&&... args) {
    if (size_ == N) return Status::kFull;
    ::new (static_cast<void*>(data() + size_)) T(std::forward<Args>(args)...);
    ++size_;
    return Status::kOk;
  }

  void pop_back() {
    SWF_ASSERT(size_ > 0);
    if (size_ == 0) return;
    --size_;
    data()[size_].~T();
  }

  // Removes element i keeping the order of the rest (O(n)).
  void erase(std::size_t i) {
    SWF_ASSERT(i < size_);
    if (i >= size_) return;
    for (std::size_t k = i; k + 1 < size_; ++k) data()[k] = std::move(data()[k + 1]);
    pop_back();
  }

  // Removes element i by moving the last element into its place (O(1), order not kept).
  void swap_erase(std::size_t i) {
    SWF_ASSERT(i < size_);
    if (i >= size_) return;
    if (i + 1 != size_) data()[i] = std::move(data()[size_ - 1]);
    pop_back();
  }

  void clear() {
    while (size_ > 0) pop_back();
  }

  T& operator[](std::size_t i) {
    SWF_ASSERT(i < size_);
    return data()[i];
  }
  const T& operator[](std::size_t i) const {
    SWF_ASSERT(i < size_);
    return data()[i];
  }
  T& back() { return (*this)[size_ - 1]; }
  const T& back() const { return (*this)[size_ - 1]; }

  T* data() { return std::launder(reinterpret_cast<T*>(storage_)); }
  const T* data() const { return std::launder(reinterpret_cast<const T*>(storage_)); }
  iterator begin() { return data(); }
  iterator end() { return data() + size_; }
  const_iterator begin() const { return data(); }
  const_iterator end() const { return data() + size_; }

 private:
  void CopyFrom(const StaticVector& other) {
    for (const T& v : other) (void)push_back(v);
  }

  alignas(T) unsigned char storage_[sizeof(T) * N];
  std::size_t size_ = 0;
};

}  // namespace swf::core
