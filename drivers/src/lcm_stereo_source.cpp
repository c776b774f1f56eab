#include "swf/drivers/lcm_stereo_source.hpp"

#include <lcm/lcm.h>

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <utility>

#include "swf/drivers/stereo_frame_message.hpp"
#include "swf/messages/checked_decode.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace swf::drivers {

namespace {
// How long the receiving thread waits in LCM before it looks at the stop flag again.
constexpr int kReceivePollMs = 50;
}  // namespace

// The LCM C API rather than lcm-cpp: its handler gets the channel as a C string, where lcm-cpp
// builds a std::string per message (an allocation for names past the small-string buffer).
struct LcmStereoSource::Impl {
  lcm_t* lcm = nullptr;
  lcm_subscription_t* subscription = nullptr;
  swf_msgs::stereo_frame_t msg;  // decode target; its images are swapped with a free slot's
};

LcmStereoSource::LcmStereoSource() : impl_(std::make_unique<Impl>()) {}

LcmStereoSource::~LcmStereoSource() { Stop(); }

core::Status LcmStereoSource::Fail(core::Status status, const char* format, ...) {
  va_list args;
  va_start(args, format);
  std::vsnprintf(error_, sizeof error_, format, args);
  va_end(args);
  return status;
}

core::Status LcmStereoSource::Configure(const LcmStereoOptions& options) {
  if (running_) {
    return Fail(core::Status::kNotConfigured, "lcm %s: Configure() while running: Stop() first",
                options_.channel.c_str());
  }
  if (num_held_ > 0) {
    return Fail(core::Status::kInvalidArgument,
                "lcm %s: Configure() while the caller holds %d pairs: release them first",
                options_.channel.c_str(), num_held_);
  }
  configured_ = false;
  const char* channel = options.channel.c_str();
  if (options.url.empty())
    return Fail(core::Status::kInvalidArgument, "lcm %s: empty url", channel);
  if (options.channel.empty()) return Fail(core::Status::kInvalidArgument, "lcm: empty channel");
  if (options.max_width < 1 || options.max_width > messages::kMaxImageSidePx ||
      options.max_height < 1 || options.max_height > messages::kMaxImageSidePx) {
    return Fail(core::Status::kInvalidArgument,
                "lcm %s: image size %" PRId32 "x%" PRId32 " outside [1, %" PRId32 "] px", channel,
                options.max_width, options.max_height, messages::kMaxImageSidePx);
  }
  if (options.buffers < 2 || options.buffers > kMaxLcmBuffers) {
    return Fail(core::Status::kInvalidArgument,
                "lcm %s: buffers %" PRId32 " outside [2, %" PRId32 "]", channel, options.buffers,
                kMaxLcmBuffers);
  }
  options_ = options;
  const auto bytes =
      static_cast<std::size_t>(options.max_width) * static_cast<std::size_t>(options.max_height);
  slots_.assign(static_cast<std::size_t>(options.buffers), Slot{});
  for (Slot& s : slots_) {
    s.left.reserve(bytes);
    s.right.reserve(bytes);
  }
  impl_->msg = swf_msgs::stereo_frame_t{};
  impl_->msg.left.reserve(bytes);
  impl_->msg.right.reserve(bytes);
  configured_ = true;
  error_[0] = '\0';
  return core::Status::kOk;
}

core::Status LcmStereoSource::Start() {
  if (!configured_) return Fail(core::Status::kNotConfigured, "lcm: Start() before Configure()");
  if (running_) return core::Status::kOk;
  const char* channel = options_.channel.c_str();
  impl_->lcm = lcm_create(options_.url.c_str());
  if (impl_->lcm == nullptr) {
    return Fail(core::Status::kIoError, "lcm %s: cannot open LCM at '%s'", channel,
                options_.url.c_str());
  }
  impl_->subscription = lcm_subscribe(
      impl_->lcm, channel,
      [](const lcm_recv_buf_t* rbuf, const char* /*channel*/, void* self) {
        static_cast<LcmStereoSource*>(self)->OnMessage(rbuf->data, rbuf->data_size);
      },
      this);
  if (impl_->subscription == nullptr) {
    lcm_destroy(impl_->lcm);
    impl_->lcm = nullptr;
    return Fail(core::Status::kIoError, "lcm %s: cannot subscribe at '%s'", channel,
                options_.url.c_str());
  }
  // Frames queued before a restart are stale: every buffer the caller does not hold is free.
  std::int32_t index = 0;
  while (ready_.TryPop(&index) == core::Status::kOk) {
  }
  while (ready_count_.try_acquire()) {
  }
  while (free_.TryPop(&index) == core::Status::kOk) {
  }
  for (std::int32_t i = 0; i < options_.buffers; ++i) {
    if (!held_[i]) (void)free_.TryPush(i);  // capacity kMaxLcmBuffers >= buffers
  }
  has_last_ = false;
  has_queued_ = false;
  rejected_since_last_ = 0;
  quit_.store(false);
  thread_ = std::thread([this] {
    while (!quit_.load(std::memory_order_relaxed)) {
      // A failing provider (its socket gone) must not spin: wait as if it had timed out.
      if (lcm_handle_timeout(impl_->lcm, kReceivePollMs) < 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(kReceivePollMs));
      }
    }
  });
  running_ = true;
  error_[0] = '\0';
  return core::Status::kOk;
}

void LcmStereoSource::Stop() {
  if (!running_) return;
  quit_.store(true);
  if (thread_.joinable()) thread_.join();
  lcm_unsubscribe(impl_->lcm, impl_->subscription);
  lcm_destroy(impl_->lcm);
  impl_->subscription = nullptr;
  impl_->lcm = nullptr;
  running_ = false;
}

void LcmStereoSource::Reject(std::atomic<std::uint64_t>* counter, const char* format, ...) {
  counter->fetch_add(1, std::memory_order_relaxed);
  if (counter != &pool_full_) ++rejected_since_last_;
  const std::lock_guard<std::mutex> lock(reject_mutex_);
  va_list args;
  va_start(args, format);
  std::vsnprintf(reject_, sizeof reject_, format, args);
  va_end(args);
}

// The receiving thread: one message, decoded into a free slot or counted.
void LcmStereoSource::OnMessage(const void* data, std::size_t size) {
  received_.fetch_add(1, std::memory_order_relaxed);
  swf_msgs::stereo_frame_t& msg = impl_->msg;
  const char* channel = options_.channel.c_str();
  const messages::DecodeError decoded =
      messages::CheckedDecode(data, size, options_.max_width, options_.max_height, &msg);
  if (!decoded.Ok()) {
    char what[96];
    messages::Describe(decoded, what, sizeof what);
    const bool too_large =
        decoded.result == messages::DecodeResult::kOverLimit &&
        (std::strcmp(decoded.field, "width") == 0 || std::strcmp(decoded.field, "height") == 0);
    if (too_large) {
      Reject(&wrong_size_,
             "lcm %s: a frame refused: %s (the buffers hold %" PRId32 "x%" PRId32 " px)", channel,
             what, options_.max_width, options_.max_height);
    } else {
      Reject(&undecodable_,
             "lcm %s: a message of %zu bytes refused: stereo_frame_t does not decode (%s)", channel,
             size, what);
    }
    return;
  }
  char why[96];
  if (!CheckStereoFrameFields(msg, why, sizeof why)) {
    Reject(&bad_fields_, "lcm %s: frame seq %" PRId64 " refused: %s", channel, msg.seq, why);
    return;
  }
  if (options_.exact_size &&
      (msg.width != options_.max_width || msg.height != options_.max_height)) {
    Reject(&wrong_size_,
           "lcm %s: frame seq %" PRId64 " refused: %" PRId32 "x%" PRId32 " px, expected %" PRId32
           "x%" PRId32,
           channel, msg.seq, msg.width, msg.height, options_.max_width, options_.max_height);
    return;
  }
  if (msg.rectified != options_.rectified) {
    Reject(&wrong_rectification_, "lcm %s: frame seq %" PRId64 " refused: %s, expected %s frames",
           channel, msg.seq, msg.rectified ? "rectified" : "raw",
           options_.rectified ? "rectified" : "raw");
    return;
  }
  // In range (CheckStereoFrameFields): no overflow.
  const core::TimeNs left_ns = msg.left_exposure_utime * core::kNsPerUs;
  const core::TimeNs right_ns = msg.right_exposure_utime * core::kNsPerUs;
  if (has_last_) {
    if (msg.seq == last_seq_ || left_ns <= last_left_ns_) {
      Reject(&out_of_order_, "lcm %s: frame seq %" PRId64 " refused: %s", channel, msg.seq,
             msg.seq == last_seq_ ? "repeated sequence number"
                                  : "exposure not after the previous frame's");
      return;
    }
    announced_drops_.fetch_add(static_cast<std::uint64_t>(msg.dropped_before),
                               std::memory_order_relaxed);
    if (msg.seq > last_seq_) {
      // Messages rejected since the previous frame arrived with numbers of their own: a gap
      // they fill was not lost on the way (they are counted as rejected).
      std::int64_t unannounced = 0;
      (void)PairsLostBefore(msg.seq - last_seq_ - 1, msg.dropped_before, &unannounced);
      const std::int64_t lost = std::max<std::int64_t>(0, unannounced - rejected_since_last_);
      sequence_gaps_.fetch_add(static_cast<std::uint64_t>(lost), std::memory_order_relaxed);
    } else {
      // Time goes on, the numbering starts again: the publisher restarted.
      publisher_restarts_.fetch_add(1, std::memory_order_relaxed);
      has_queued_ = false;
    }
  }
  has_last_ = true;
  rejected_since_last_ = 0;
  last_seq_ = msg.seq;
  last_left_ns_ = left_ns;

  std::int32_t index = 0;
  if (free_.TryPop(&index) != core::Status::kOk) {
    Reject(&pool_full_, "lcm %s: frame seq %" PRId64 " dropped: every buffer is queued or held",
           channel, msg.seq);
    return;
  }
  Slot& slot = slots_[static_cast<std::size_t>(index)];
  // Both vectors keep the capacity reserved in Configure(): the swap allocates nothing.
  std::swap(slot.left, msg.left);
  std::swap(slot.right, msg.right);
  slot.width = msg.width;
  slot.height = msg.height;
  slot.left_ns = left_ns;
  slot.right_ns = right_ns;
  slot.seq = static_cast<std::uint64_t>(msg.seq);
  std::int64_t unannounced = 0;
  // The pairs lost since the previous one queued (those dropped here for want of a buffer
  // included); the first after Start() has no previous pair.
  slot.dropped_before = !has_queued_ ? 0
                                     : PairsLostBefore(msg.seq - last_queued_seq_ - 1,
                                                       msg.dropped_before, &unannounced);
  has_queued_ = true;
  last_queued_seq_ = msg.seq;
  (void)ready_.TryPush(index);  // capacity kMaxLcmBuffers >= buffers: never full
  ready_count_.release();
}

core::Status LcmStereoSource::Next(core::TimeNs timeout_ns, StereoPair* pair) {
  if (!running_) {
    return Fail(core::Status::kNotConfigured, "lcm %s: Next() before Start()",
                options_.channel.c_str());
  }
  if (num_held_ >= options_.buffers) {
    return Fail(core::Status::kFull, "lcm %s: the caller holds all %" PRId32 " buffers",
                options_.channel.c_str(), options_.buffers);
  }
  const bool ready = timeout_ns <= 0
                         ? ready_count_.try_acquire()
                         : ready_count_.try_acquire_for(std::chrono::nanoseconds(timeout_ns));
  std::int32_t index = 0;
  if (!ready || ready_.TryPop(&index) != core::Status::kOk) {
    ++timeouts_;
    // The receiver's last complaint, unless it is writing one right now (never wait on it).
    char last[sizeof reject_] = "";
    if (reject_mutex_.try_lock()) {
      std::memcpy(last, reject_, sizeof last);
      reject_mutex_.unlock();
    }
    const SourceStats s = Stats();
    std::snprintf(error_, sizeof error_,
                  "lcm %s: no frame within %" PRId64 " ms (%" PRIu64 " messages received, %" PRIu64
                  " rejected, %" PRIu64 " dropped)%s%s",
                  options_.channel.c_str(), timeout_ns / core::kNsPerMs,
                  received_.load(std::memory_order_relaxed), s.frames_rejected, s.frames_dropped,
                  last[0] != '\0' ? "; last: " : "", last);
    return core::Status::kTimeout;
  }
  const Slot& slot = slots_[static_cast<std::size_t>(index)];
  pair->left =
      core::ImageView<const std::uint8_t>{slot.left.data(), slot.width, slot.height, slot.width};
  pair->right =
      core::ImageView<const std::uint8_t>{slot.right.data(), slot.width, slot.height, slot.width};
  pair->left_exposure_ns = slot.left_ns;
  pair->right_exposure_ns = slot.right_ns;
  pair->seq = slot.seq;
  pair->dropped_before = slot.dropped_before;
  pair->handle = index;
  held_[index] = true;
  ++num_held_;
  ++pairs_served_;
  return core::Status::kOk;
}

void LcmStereoSource::Release(const StereoPair& pair) {
  const std::int32_t h = pair.handle;
  if (h < 0 || h >= static_cast<std::int32_t>(slots_.size()) || !held_[h]) return;
  held_[h] = false;
  --num_held_;
  (void)free_.TryPush(h);  // capacity kMaxLcmBuffers >= buffers: never full
}

LcmStereoStats LcmStereoSource::Detail() const {
  LcmStereoStats d;
  d.received = received_.load(std::memory_order_relaxed);
  d.undecodable = undecodable_.load(std::memory_order_relaxed);
  d.wrong_size = wrong_size_.load(std::memory_order_relaxed);
  d.bad_fields = bad_fields_.load(std::memory_order_relaxed);
  d.wrong_rectification = wrong_rectification_.load(std::memory_order_relaxed);
  d.out_of_order = out_of_order_.load(std::memory_order_relaxed);
  d.announced_drops = announced_drops_.load(std::memory_order_relaxed);
  d.sequence_gaps = sequence_gaps_.load(std::memory_order_relaxed);
  d.pool_full = pool_full_.load(std::memory_order_relaxed);
  d.publisher_restarts = publisher_restarts_.load(std::memory_order_relaxed);
  return d;
}

SourceStats LcmStereoSource::Stats() const {
  const LcmStereoStats d = Detail();
  SourceStats s;
  s.pairs_served = pairs_served_;
  s.frames_rejected =
      d.undecodable + d.wrong_size + d.bad_fields + d.wrong_rectification + d.out_of_order;
  s.frames_dropped = d.announced_drops + d.sequence_gaps + d.pool_full;
  s.timeouts = timeouts_;
  return s;
}

}  // namespace swf::drivers
