// SpscQueue<T, N>: bounded lock-free queue for exactly one producer thread and one consumer
// thread. The real-time loop pushes outputs with TryPush (never blocks, never allocates); the
// publisher thread drains with TryPop. A full queue is a counted, reported drop by the caller.
#pragma once

#include <atomic>
#include <cstddef>
#include <new>

#include "swf/core/status.hpp"

namespace swf::core {

template <typename T, std::size_t N>
class SpscQueue {
  static_assert(N >= 1, "capacity must be positive");
  // One slot stays empty to tell full from empty without a shared counter.
  static constexpr std::size_t kSlots = N + 1;
  // Fixed rather than std::hardware_destructive_interference_size, whose value may differ
  // between compilers and would make the layout depend on flags.
  static constexpr std::size_t kCacheLine = 64;

 public:
  static constexpr std::size_t capacity() { return N; }

  // Producer side. kFull when the consumer has not caught up; the value is not taken.
  Status TryPush(const T& value) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t next = Next(tail);
    if (next == head_.load(std::memory_order_acquire)) return Status::kFull;
    slots_[tail] = value;
    tail_.store(next, std::memory_order_release);
    return Status::kOk;
  }

  // Consumer side. kEmpty when nothing is queued.
  Status TryPop(T* out) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) return Status::kEmpty;
    *out = slots_[head];
    head_.store(Next(head), std::memory_order_release);
    return Status::kOk;
  }

  // Either side; a snapshot that may be stale by the time it is read.
  std::size_t SizeApprox() const {
    const std::size_t head = head_.load(std::memory_order_acquire);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    return (tail + kSlots - head) % kSlots;
  }

 private:
  static constexpr std::size_t Next(std::size_t i) { return (i + 1) % kSlots; }

  alignas(kCacheLine) std::atomic<std::size_t> head_{0};  // written by the consumer
  alignas(kCacheLine) std::atomic<std::size_t> tail_{0};  // written by the producer
  alignas(kCacheLine) T slots_[kSlots]{};
};

}  // namespace swf::core
