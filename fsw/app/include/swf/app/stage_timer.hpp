// StageStats: per-stage timing of the frame group without allocation. The last kWindow samples
// are kept in a ring; p50/p99 come from a copy partially sorted into a member scratch array
// (called at the health rate, not per frame); the maximum covers the whole run.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "swf/core/ring_buffer.hpp"
#include "swf/core/time.hpp"

namespace swf::app {

struct StageSummary {
  float p50_ms = 0.0f;
  float p99_ms = 0.0f;
  float max_ms = 0.0f;
  std::uint64_t samples = 0;
};

class StageStats {
 public:
  static constexpr std::size_t kWindow = 4096;

  void Add(core::TimeNs duration_ns) {
    (void)samples_.PushOverwrite(duration_ns);
    max_ns_ = std::max(max_ns_, duration_ns);
    ++count_;
  }

  // Percentiles over the last kWindow samples (nearest rank), maximum over the run.
  StageSummary Summarize() {
    StageSummary s;
    const std::size_t n = samples_.size();
    s.samples = count_;
    s.max_ms = static_cast<float>(core::NsToMs(max_ns_));
    if (n == 0) return s;
    for (std::size_t i = 0; i < n; ++i) scratch_[i] = samples_[i];
    s.p50_ms = static_cast<float>(core::NsToMs(Rank(n, 50)));
    s.p99_ms = static_cast<float>(core::NsToMs(Rank(n, 99)));
    return s;
  }

  void Reset() {
    samples_.Clear();
    max_ns_ = 0;
    count_ = 0;
  }

 private:
  core::TimeNs Rank(std::size_t n, std::size_t percent) {
    // Nearest-rank percentile: the smallest value with at least percent% of samples <= it.
    std::size_t k = (percent * n + 99) / 100;
    k = k == 0 ? 0 : k - 1;
    std::nth_element(scratch_, scratch_ + k, scratch_ + n);
    return scratch_[k];
  }

  core::RingBuffer<core::TimeNs, kWindow> samples_;
  core::TimeNs scratch_[kWindow] = {};
  core::TimeNs max_ns_ = 0;
  std::uint64_t count_ = 0;
};

}  // namespace swf::app
