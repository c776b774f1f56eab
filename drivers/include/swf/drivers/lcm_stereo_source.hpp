// LcmStereoSource: stereo pairs published live as stereo_frame_t on an LCM channel (a camera
// process on another computer, the simulator's SimLcmPublisher) behind the StereoSource
// interface.
//
// A receiving thread (normal priority) subscribes to the channel with LCM's raw handler and takes
// each message through the same checks a log's frames get: the checked decoder
// (swf/messages/checked_decode.hpp) within the configured image size, then the fields
// (CheckStereoFrameFields), the expected size and rectification, and the sequence (drivers/
// stereo_frame_message.hpp). A usable frame is decoded straight into a free buffer of a fixed pool
// and its index queued (core::SpscQueue) for Next(); Release() queues the index back. Nothing the
// publisher sends can stop the source: every frame that is not served is counted.
//
//   frames_rejected  does not decode (truncated, another type, bad lengths), larger than
//                    max_width x max_height (or not exactly that size with exact_size), empty or
//                    out-of-range fields, the other `rectified` flag than expected, a repeated
//                    sequence number or an exposure not after the previous frame's
//   frames_dropped   pairs lost before reaching the consumer: announced by the publisher (its
//                    dropped_before), missing from the sequence (lost on the network; a gap
//                    no larger than the messages rejected meanwhile is theirs, not a loss), or
//                    arriving while every buffer is queued or held (the consumer fell behind)
//
// Each served pair's dropped_before is the pairs lost since the previous served pair, whatever
// lost them (the frame group coasts across them). A sequence number going back while the exposure
// time advances is the publisher restarting its count: followed, nothing counted.
//
// Memory: the pool (`buffers` pairs of max_width x max_height bytes each, plus the decode
// target) is allocated in Configure(); Next() and Release() never allocate, and neither does
// this source's handler on the receiving thread (LCM's own receive thread may, for messages
// it reassembles from fragments). Start() opens LCM and starts the thread (allocates); Stop()
// joins it and closes LCM. A pair held across Stop() / Start() stays valid and is released as
// usual.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <semaphore>
#include <string>
#include <thread>
#include <vector>

#include "swf/core/spsc_queue.hpp"
#include "swf/drivers/stereo_source.hpp"

namespace swf::drivers {

// Pair buffers a source may have (the queues' compiled capacity).
inline constexpr std::int32_t kMaxLcmBuffers = 16;

struct LcmStereoOptions {
  std::string url;      // LCM provider, e.g. "udpm://239.255.76.67:7667?ttl=0"
  std::string channel;  // stereo_frame_t channel, e.g. "SWF_STEREO"
  // Largest image the pool holds; larger frames are rejected before they are decoded.
  std::int32_t max_width = 0;
  std::int32_t max_height = 0;
  // Frames must be exactly max_width x max_height (a camera of known size; the pipeline's
  // rectification maps are built for one size).
  bool exact_size = false;
  // The `rectified` flag every frame must carry: false when the consumer rectifies raw frames
  // with its calibrations (as for an unrectified log), true when it needs rectified ones.
  bool rectified = false;
  // Pairs in the pool, [2, kMaxLcmBuffers]: the consumer may hold all but one while the receiver
  // fills the last.
  std::int32_t buffers = 4;
};

// What the receiving thread saw (frames_rejected and frames_dropped itemised).
struct LcmStereoStats {
  std::uint64_t received = 0;             // messages on the channel
  std::uint64_t undecodable = 0;          // rejected: the checked decoder refused them
  std::uint64_t wrong_size = 0;           // rejected: larger than the pool, or not the exact size
  std::uint64_t bad_fields = 0;           // rejected: empty image, negative seq, stamp range
  std::uint64_t wrong_rectification = 0;  // rejected: the other `rectified` flag
  std::uint64_t out_of_order = 0;         // rejected: repeated seq or exposure not advancing
  std::uint64_t announced_drops = 0;      // dropped: the publisher's dropped_before
  std::uint64_t sequence_gaps = 0;        // dropped: missing sequence numbers (the network)
  std::uint64_t pool_full = 0;            // dropped: no free buffer
  std::uint64_t publisher_restarts = 0;   // sequence went back with time advancing
};

class LcmStereoSource final : public StereoSource {
 public:
  LcmStereoSource();
  ~LcmStereoSource() override;
  LcmStereoSource(const LcmStereoSource&) = delete;
  LcmStereoSource& operator=(const LcmStereoSource&) = delete;

  // Checks the options and allocates the pool (before Start() or after Stop()).
  // kInvalidArgument with LastError() naming the option; kNotConfigured while running.
  core::Status Configure(const LcmStereoOptions& options);

  // kNotConfigured before Configure(); kIoError when LCM cannot be opened or subscribed (the URL
  // named). Frames queued before a Stop() are discarded: a restart serves what arrives after it.
  core::Status Start() override;
  // Waits at most timeout_ns (<= 0: does not wait) for a pair. kOk, kTimeout (LastError says
  // how long and what was rejected meanwhile), kFull when the caller holds every buffer,
  // kNotConfigured when not started.
  core::Status Next(core::TimeNs timeout_ns, StereoPair* pair) override;
  // Unknown or already released handles are ignored.
  void Release(const StereoPair& pair) override;
  void Stop() override;
  SourceStats Stats() const override;
  const char* Name() const override { return "lcm"; }
  const char* LastError() const override { return error_; }

  LcmStereoStats Detail() const;

 private:
  struct Impl;
  struct Slot {
    std::vector<std::uint8_t> left;  // reserved to max_width x max_height: swapped, never grown
    std::vector<std::uint8_t> right;
    std::int32_t width = 0;
    std::int32_t height = 0;
    core::TimeNs left_ns = 0;
    core::TimeNs right_ns = 0;
    std::uint64_t seq = 0;
    std::uint32_t dropped_before = 0;
  };
  // Receiving thread.
  void OnMessage(const void* data, std::size_t size);
  void Reject(std::atomic<std::uint64_t>* counter, const char* format, ...)
      __attribute__((format(printf, 3, 4)));
  core::Status Fail(core::Status status, const char* format, ...)
      __attribute__((format(printf, 3, 4)));

  LcmStereoOptions options_;
  bool configured_ = false;
  bool running_ = false;
  std::unique_ptr<Impl> impl_;  // LCM and the decode target
  std::vector<Slot> slots_;
  // Pool indices: ready_ from the receiver to the consumer (ready_count_ wakes it), free_ back.
  core::SpscQueue<std::int32_t, kMaxLcmBuffers> ready_;
  core::SpscQueue<std::int32_t, kMaxLcmBuffers> free_;
  std::counting_semaphore<kMaxLcmBuffers> ready_count_{0};
  bool held_[kMaxLcmBuffers] = {};  // consumer side: handed out by Next(), not yet released
  std::int32_t num_held_ = 0;
  std::atomic<bool> quit_{false};
  std::thread thread_;

  // Receiving thread's sequence state (reset by Start()).
  bool has_last_ = false;
  std::int64_t last_seq_ = 0;
  core::TimeNs last_left_ns_ = 0;
  bool has_queued_ = false;
  std::int64_t last_queued_seq_ = 0;
  std::int64_t rejected_since_last_ = 0;  // messages rejected since the last in sequence

  // Counters: the receiving thread's (atomic) and the consumer's.
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> undecodable_{0};
  std::atomic<std::uint64_t> wrong_size_{0};
  std::atomic<std::uint64_t> bad_fields_{0};
  std::atomic<std::uint64_t> wrong_rectification_{0};
  std::atomic<std::uint64_t> out_of_order_{0};
  std::atomic<std::uint64_t> announced_drops_{0};
  std::atomic<std::uint64_t> sequence_gaps_{0};
  std::atomic<std::uint64_t> pool_full_{0};
  std::atomic<std::uint64_t> publisher_restarts_{0};
  std::uint64_t pairs_served_ = 0;
  std::uint64_t timeouts_ = 0;

  // Why the last frame was rejected (receiving thread, under reject_mutex_; the consumer only
  // try-locks it, so it never waits on the receiver), and the consumer's LastError().
  mutable std::mutex reject_mutex_;
  char reject_[160] = "";
  char error_[320] = "";
};

}  // namespace swf::drivers
