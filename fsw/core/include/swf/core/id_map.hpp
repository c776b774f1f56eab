// IdMap<kCapacity>: a fixed-capacity map from 64-bit ids to small non-negative integers (slots),
// with storage inside the object. Open addressing with linear probing in a power-of-two table at
// least twice the capacity, so a probe sequence always ends at an empty entry; deletion shifts
// the following cluster back instead of leaving tombstones, so lookups stay short however many
// ids come and go (a landmark id lives for a few frames in a descent of thousands).
#pragma once

#include <cstdint>

#include "swf/core/assert.hpp"

namespace swf::core {

template <int kCapacity>
class IdMap {
  static_assert(kCapacity > 0, "capacity must be positive");

 public:
  void Clear() {
    for (int i = 0; i < kSize; ++i) used_[i] = false;
    count_ = 0;
  }

  int size() const { return count_; }

  // The value stored for `key`, or -1.
  int Find(std::int64_t key) const {
    for (int i = Hash(key), n = 0; n < kSize; i = Next(i), ++n) {
      if (!used_[i]) return -1;
      if (keys_[i] == key) return values_[i];
    }
    return -1;
  }

  // Stores or replaces the value for `key`. The caller keeps at most kCapacity keys (asserted).
  void Insert(std::int64_t key, int value) {
    for (int i = Hash(key), n = 0; n < kSize; i = Next(i), ++n) {
      if (used_[i] && keys_[i] != key) continue;
      if (!used_[i]) ++count_;
      SWF_ASSERT(count_ <= kCapacity);
      used_[i] = true;
      keys_[i] = key;
      values_[i] = value;
      return;
    }
    SWF_ASSERT(false);  // cannot happen: the table holds twice the capacity
  }

  // Removes `key` if present.
  void Erase(std::int64_t key) {
    int i = Hash(key);
    for (int n = 0; n < kSize && used_[i] && keys_[i] != key; ++n) i = Next(i);
    if (!used_[i] || keys_[i] != key) return;
    // Move back every later key of the cluster whose home lies at or before the hole, so that
    // each remaining key is still reached from its home without crossing an empty entry.
    int hole = i;
    for (int j = Next(i), n = 0; n < kSize && used_[j]; j = Next(j), ++n) {
      const int home = Hash(keys_[j]);
      const bool movable = hole <= j ? (home <= hole || home > j) : (home <= hole && home > j);
      if (movable) {
        keys_[hole] = keys_[j];
        values_[hole] = values_[j];
        hole = j;
      }
    }
    used_[hole] = false;
    --count_;
  }

 private:
  static constexpr int kSize = [] {
    int s = 1;
    while (s < 2 * kCapacity) s <<= 1;
    return s;
  }();

  static int Next(int i) { return (i + 1) & (kSize - 1); }

  // splitmix64's finalizer: consecutive ids (as trackers hand them out) spread over the table.
  static int Hash(std::int64_t key) {
    std::uint64_t x = static_cast<std::uint64_t>(key) + 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    x ^= x >> 31;
    return static_cast<int>(x & static_cast<std::uint64_t>(kSize - 1));
  }

  std::int64_t keys_[kSize];
  int values_[kSize];
  bool used_[kSize] = {};
  int count_ = 0;
};

}  // namespace swf::core
