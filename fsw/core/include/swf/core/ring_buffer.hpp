// RingBuffer<T, N>: fixed-capacity FIFO with storage inside the object, for histories (timing
// samples, recent frames). Single-threaded; for crossing threads use SpscQueue.
#pragma once

#include <cstddef>

#include "swf/core/assert.hpp"
#include "swf/core/status.hpp"

namespace swf::core {

template <typename T, std::size_t N>
class RingBuffer {
  static_assert(N > 0, "capacity must be positive");

 public:
  static constexpr std::size_t capacity() { return N; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == N; }

  // Appends at the back; kFull (buffer unchanged) when full.
  Status Push(const T& value) {
    if (size_ == N) return Status::kFull;
    items_[(head_ + size_) % N] = value;
    ++size_;
    return Status::kOk;
  }

  // Appends at the back, dropping the oldest element when full. Returns true if one was dropped.
  bool PushOverwrite(const T& value) {
    if (size_ < N) {
      (void)Push(value);
      return false;
    }
    items_[head_] = value;
    head_ = (head_ + 1) % N;
    return true;
  }

  // Removes the oldest element into *out; kEmpty when there is none.
  Status Pop(T* out) {
    if (size_ == 0) return Status::kEmpty;
    if (out != nullptr) *out = items_[head_];
    head_ = (head_ + 1) % N;
    --size_;
    return Status::kOk;
  }

  // Element i counted from the oldest (0) to the newest (size()-1).
  const T& operator[](std::size_t i) const {
    SWF_ASSERT(i < size_);
    return items_[(head_ + i) % N];
  }
  T& operator[](std::size_t i) {
    SWF_ASSERT(i < size_);
    return items_[(head_ + i) % N];
  }
  const T& front() const { return (*this)[0]; }
  const T& back() const { return (*this)[size_ - 1]; }

  void Clear() {
    head_ = 0;
    size_ = 0;
  }

 private:
  T items_[N]{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

}  // namespace swf::core
