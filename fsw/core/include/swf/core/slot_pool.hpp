// SlotPool<T, N>: N objects of T allocated once at start-up, handed between exactly two
// threads by index. The producer acquires a free slot, fills it and passes the index on (e.g.
// through an SpscQueue); the consumer reads it and releases it back. Large records (frames,
// maps) thus cross threads without copying and without allocating after start.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>

#include "swf/core/spsc_queue.hpp"
#include "swf/core/status.hpp"

namespace swf::core {

template <typename T, std::size_t N>
class SlotPool {
 public:
  // Start-up only: the one allocation. kFull when memory is short.
  Status Allocate() {
    slots_.reset(new (std::nothrow) T[N]);
    free_.reset(new (std::nothrow) SpscQueue<std::int32_t, N>());
    if (!slots_ || !free_) return Status::kFull;
    for (std::size_t i = 0; i < N; ++i) (void)free_->TryPush(static_cast<std::int32_t>(i));
    return Status::kOk;
  }
  // Producer: a free slot index, or -1 when every slot is still with the consumer.
  std::int32_t Acquire() {
    std::int32_t i = -1;
    return free_->TryPop(&i) == Status::kOk ? i : -1;
  }
  // Consumer: gives a slot back.
  void Release(std::int32_t i) { (void)free_->TryPush(i); }
  T& operator[](std::int32_t i) { return slots_[i]; }
  const T& operator[](std::int32_t i) const { return slots_[i]; }
  static constexpr std::size_t capacity() { return N; }

 private:
  std::unique_ptr<T[]> slots_;
  std::unique_ptr<SpscQueue<std::int32_t, N>> free_;
};

}  // namespace swf::core
