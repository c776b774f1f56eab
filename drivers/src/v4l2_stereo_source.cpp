#include "swf/drivers/v4l2_stereo_source.hpp"

#include <poll.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>

namespace swf::drivers {
namespace {

// Upper bound on dequeue/discard rounds in one Next(): a device spewing bad frames must not keep
// the flight loop inside Next() forever (the timeout is checked too, but only between rounds).
constexpr int kMaxRoundsPerNext = 256;

}  // namespace

V4l2StereoSource::V4l2StereoSource(V4l2Kernel& kernel)
    : kernel_(&kernel), left_(kernel), right_(kernel) {}

V4l2StereoSource::~V4l2StereoSource() { Stop(); }

core::Status V4l2StereoSource::Configure(const V4l2StereoOptions& options) {
  configured_ = false;
  if (options.max_pairs_held < 1 || options.max_pairs_held > kMaxPairsHeld ||
      options.pair_tolerance_ns < 0 || options.max_consecutive_io_errors < 1 ||
      options.left.device == nullptr ||
      (!options.side_by_side && options.right.device == nullptr)) {
    std::snprintf(last_error_, sizeof(last_error_), "v4l2: invalid options");
    return core::Status::kInvalidArgument;
  }
  // Zero-copy pairs keep driver buffers dequeued; the kernel needs at least two more to stream.
  if (options.left.buffer_count < options.max_pairs_held + 2 ||
      (!options.side_by_side && options.right.buffer_count < options.max_pairs_held + 2)) {
    std::snprintf(last_error_, sizeof(last_error_),
                  "v4l2: buffer_count must be >= max_pairs_held + 2");
    return core::Status::kInvalidArgument;
  }
  options_ = options;
  configured_ = true;
  return core::Status::kOk;
}

core::Status V4l2StereoSource::Error(core::Status status, const char* what,
                                     const V4l2Camera& camera) {
  const char* device = &camera == &right_ ? options_.right.device : options_.left.device;
  std::snprintf(last_error_, sizeof(last_error_), "v4l2 %s: %s: %s (errno %d: %s)", device, what,
                core::ToString(status), camera.LastErrno(), std::strerror(camera.LastErrno()));
  return status;
}

core::Status V4l2StereoSource::Start() {
  if (!configured_) return core::Status::kNotConfigured;
  Stop();
  core::Status s = left_.Open(options_.left);
  if (!core::IsOk(s)) return Error(s, "open", left_);
  if (!options_.side_by_side) {
    s = right_.Open(options_.right);
    if (!core::IsOk(s)) {
      left_.Close();
      return Error(s, "open", right_);
    }
  }
  if (options_.side_by_side && left_.Desc().width % 2 != 0) {
    left_.Close();
    std::snprintf(last_error_, sizeof(last_error_), "v4l2 %s: side-by-side width %d is odd",
                  options_.left.device, left_.Desc().width);
    return core::Status::kUnsupported;
  }
  // Conversion targets for every slot, sized from what the devices actually negotiated.
  for (std::int32_t i = 0; i < options_.max_pairs_held; ++i) {
    Slot& slot = slots_[i];
    slot = Slot{};
    for (int side = 0; side < 2; ++side) {
      const SourceImageDesc& d = options_.side_by_side ? left_.Desc() : Camera(side).Desc();
      const std::size_t bytes = static_cast<std::size_t>(d.width) * d.height;
      auto& gray = side == kLeft ? slot.left_gray : slot.right_gray;
      gray.reset(new (std::nothrow) std::uint8_t[bytes]);
      if (!gray) {
        Stop();
        std::snprintf(last_error_, sizeof(last_error_), "v4l2: out of memory for pair slots");
        return core::Status::kFull;
      }
    }
  }
  for (int side = 0; side < SideCount(); ++side) {
    s = Camera(side).StreamOn();
    if (!core::IsOk(s)) {
      (void)Error(s, "VIDIOC_STREAMON", Camera(side));
      Stop();
      return s;
    }
    sequence_[side].Reset();
    held_[side] = Held{};
    numbering_.Restart(side);
  }
  consecutive_io_errors_[kLeft] = consecutive_io_errors_[kRight] = 0;
  last_frame_ns_[kLeft] = last_frame_ns_[kRight] = core::MonotonicNs();
  started_ = true;
  return core::Status::kOk;
}

void V4l2StereoSource::Discard(int side) {
  if (!held_[side].valid) return;
  (void)Camera(side).Requeue(held_[side].frame.index);
  held_[side].valid = false;
}

core::Status V4l2StereoSource::Fill(int side) {
  if (held_[side].valid) return core::Status::kOk;
  V4l2Camera& camera = Camera(side);
  V4l2Frame frame;
  const core::Status s = camera.Dequeue(&frame);
  if (s == core::Status::kTimeout) return core::Status::kOk;
  last_frame_ns_[side] = core::MonotonicNs();
  if (s == core::Status::kCorruptData) {
    // EIO from DQBUF or a nonsense index: no frame, the stream goes on unless it persists.
    ++stats_.frames_rejected;
    numbering_.Lose(side);
    if (++consecutive_io_errors_[side] >= options_.max_consecutive_io_errors) {
      return Error(core::Status::kIoError, "VIDIOC_DQBUF keeps failing", camera);
    }
    return core::Status::kOk;
  }
  if (!core::IsOk(s)) return Error(s, "VIDIOC_DQBUF", camera);
  consecutive_io_errors_[side] = 0;
  const std::uint32_t lost = sequence_[side].Observe(frame.sequence);
  stats_.frames_dropped += lost;
  numbering_.Lose(side, lost);
  const SourceImageDesc& d = camera.Desc();
  if (frame.device_flagged_error || frame.bytes_used < RequiredBytes(d)) {
    ++stats_.frames_rejected;
    numbering_.Lose(side);
    const core::Status q = camera.Requeue(frame.index);
    if (!core::IsOk(q)) return Error(q, "VIDIOC_QBUF", camera);
    return core::Status::kOk;
  }
  held_[side].frame = frame;
  held_[side].valid = true;
  return core::Status::kOk;
}

core::Status V4l2StereoSource::WaitReadable(core::TimeNs remaining_ns) {
  pollfd fds[2];
  int n = 0;
  for (int side = 0; side < SideCount(); ++side) {
    if (held_[side].valid) continue;
    fds[n].fd = Camera(side).Fd();
    fds[n].events = POLLIN;
    fds[n].revents = 0;
    ++n;
  }
  if (n == 0) return core::Status::kOk;
  // Round up so a sub-millisecond remainder still waits instead of spinning.
  const int timeout_ms = static_cast<int>((remaining_ns + core::kNsPerMs - 1) / core::kNsPerMs);
  const int r = kernel_->Poll(fds, n, timeout_ms);
  if (r == 0) return core::Status::kTimeout;
  if (r == -EINTR) return core::Status::kOk;  // the caller's loop re-checks the deadline
  if (r < 0) {
    std::snprintf(last_error_, sizeof(last_error_), "v4l2: poll failed (errno %d)", -r);
    return core::Status::kIoError;
  }
  // POLLERR/POLLHUP: the next dequeue tells which error (ENODEV after an unplug).
  return core::Status::kOk;
}

core::Status V4l2StereoSource::Emit(Slot& slot, std::int32_t slot_index, StereoPair* pair) {
  const V4l2Frame& lf = held_[kLeft].frame;
  const V4l2Frame& rf = options_.side_by_side ? lf : held_[kRight].frame;
  const SourceImageDesc ld = left_.Desc();
  const SourceImageDesc rd = options_.side_by_side ? left_.Desc() : right_.Desc();
  *pair = StereoPair{};
  if (options_.side_by_side) {
    // One frame [left | right]: each view is half the columns, same rows and stride.
    SourceImageDesc half = ld;
    half.width = ld.width / 2;
    const std::size_t right_offset =
        static_cast<std::size_t>(half.width) * static_cast<std::size_t>(BytesPerPixel(ld.format));
    if (ld.format == PixelFormat::kGray8) {
      pair->left = {lf.data, half.width, half.height, half.stride_bytes};
      pair->right = {lf.data + right_offset, half.width, half.height, half.stride_bytes};
      slot.left_index = lf.index;
      held_[kLeft].valid = false;
    } else {
      core::Status s =
          ConvertToGray8(half, lf.data, lf.bytes_used, slot.left_gray.get(), half.width);
      if (core::IsOk(s)) {
        s = ConvertToGray8(half, lf.data + right_offset, lf.bytes_used - right_offset,
                           slot.right_gray.get(), half.width);
      }
      Discard(kLeft);
      if (!core::IsOk(s)) return s;
      pair->left = {slot.left_gray.get(), half.width, half.height, half.width};
      pair->right = {slot.right_gray.get(), half.width, half.height, half.width};
    }
  } else {
    const V4l2Frame* frames[2] = {&lf, &rf};
    const SourceImageDesc* descs[2] = {&ld, &rd};
    core::ImageView<const std::uint8_t>* views[2] = {&pair->left, &pair->right};
    std::int32_t* indices[2] = {&slot.left_index, &slot.right_index};
    std::uint8_t* grays[2] = {slot.left_gray.get(), slot.right_gray.get()};
    core::Status result = core::Status::kOk;
    for (int side = 0; side < 2; ++side) {
      const SourceImageDesc& d = *descs[side];
      if (d.format == PixelFormat::kGray8) {
        *views[side] = {frames[side]->data, d.width, d.height, d.stride_bytes};
        *indices[side] = frames[side]->index;
        held_[side].valid = false;
      } else {
        const core::Status s =
            ConvertToGray8(d, frames[side]->data, frames[side]->bytes_used, grays[side], d.width);
        Discard(side);
        if (!core::IsOk(s)) result = s;
        *views[side] = {grays[side], d.width, d.height, d.width};
      }
    }
    if (!core::IsOk(result)) {
      // Undo the zero-copy side so the failed pair leaks no driver buffer.
      if (slot.left_index >= 0) (void)left_.Requeue(slot.left_index);
      if (slot.right_index >= 0) (void)right_.Requeue(slot.right_index);
      slot.left_index = slot.right_index = -1;
      return result;
    }
  }
  pair->left_exposure_ns = lf.timestamp_ns;
  pair->right_exposure_ns = rf.timestamp_ns;
  ServePair(slot_index, &slot, &numbering_, &stats_, pair);
  return core::Status::kOk;
}

core::Status V4l2StereoSource::Next(core::TimeNs timeout_ns, StereoPair* pair) {
  if (!started_) return core::Status::kNotConfigured;
  if (pair == nullptr) return core::Status::kInvalidArgument;
  const std::int32_t slot_index = FreeSlot(slots_, options_.max_pairs_held);
  if (slot_index < 0) {
    std::snprintf(last_error_, sizeof(last_error_), "v4l2: all %d pair slots are held",
                  options_.max_pairs_held);
    return core::Status::kFull;
  }
  const core::TimeNs deadline_ns = core::MonotonicNs() + (timeout_ns > 0 ? timeout_ns : 0);
  for (int round = 0; round < kMaxRoundsPerNext; ++round) {
    for (int side = 0; side < SideCount(); ++side) {
      const core::Status s = Fill(side);
      if (!core::IsOk(s)) return s;
    }
    const bool have_left = held_[kLeft].valid;
    const bool have_right = options_.side_by_side ? have_left : held_[kRight].valid;
    if (have_left && have_right) {
      if (options_.side_by_side) return Emit(slots_[slot_index], slot_index, pair);
      switch (DecidePair(held_[kLeft].frame.timestamp_ns, held_[kRight].frame.timestamp_ns,
                         options_.pair_tolerance_ns)) {
        case PairDecision::kPair: {
          const core::Status s = Emit(slots_[slot_index], slot_index, pair);
          if (core::IsOk(s)) return s;
          // A frame shorter than its format (already counted as unusable): keep going.
          ++stats_.frames_rejected;
          continue;
        }
        case PairDecision::kDiscardLeft:
          ++stats_.pairing_failures;
          numbering_.Lose(kLeft);
          Discard(kLeft);
          continue;
        case PairDecision::kDiscardRight:
          ++stats_.pairing_failures;
          numbering_.Lose(kRight);
          Discard(kRight);
          continue;
      }
    }
    const core::TimeNs remaining_ns = deadline_ns - core::MonotonicNs();
    if (remaining_ns <= 0) break;
    const core::Status w = WaitReadable(remaining_ns);
    if (w == core::Status::kTimeout) break;
    if (!core::IsOk(w)) return w;
  }
  ++stats_.timeouts;
  NameSilentDevice();
  return core::Status::kTimeout;
}

void V4l2StereoSource::NameSilentDevice() {
  const core::TimeNs now = core::MonotonicNs();
  // The pair waits for the side that holds no frame; when neither does, both are silent.
  const bool left_silent = !held_[kLeft].valid;
  const bool right_silent = !options_.side_by_side && !held_[kRight].valid;
  const int side = left_silent ? kLeft : kRight;
  const char* device = side == kLeft ? options_.left.device : options_.right.device;
  const long long silent_ms = static_cast<long long>((now - last_frame_ns_[side]) / core::kNsPerMs);
  if (left_silent && right_silent) {
    std::snprintf(last_error_, sizeof(last_error_),
                  "v4l2 %s and %s: no frame from either for %lld ms (stalled or disconnected)",
                  options_.left.device, options_.right.device, silent_ms);
  } else {
    std::snprintf(last_error_, sizeof(last_error_),
                  "v4l2 %s: no frame for %lld ms (stalled or disconnected)", device, silent_ms);
  }
}

void V4l2StereoSource::Release(const StereoPair& pair) {
  if (pair.handle < 0 || pair.handle >= options_.max_pairs_held) return;
  Slot& slot = slots_[pair.handle];
  if (!slot.in_use) return;  // released twice: nothing to give back
  // A failed QBUF (device gone) is not reported here: the next Next() sees the device error.
  if (slot.left_index >= 0 && left_.Fd() >= 0) (void)left_.Requeue(slot.left_index);
  if (slot.right_index >= 0 && right_.Fd() >= 0) (void)right_.Requeue(slot.right_index);
  slot.left_index = slot.right_index = -1;
  slot.in_use = false;
}

void V4l2StereoSource::Stop() {
  held_[kLeft] = Held{};
  held_[kRight] = Held{};
  // Closing the device frees every driver buffer, including those held by unreleased pairs; their
  // views become invalid, which the interface documents (Stop ends all pairs).
  for (Slot& slot : slots_) {
    slot.in_use = false;
    slot.left_index = slot.right_index = -1;
  }
  left_.Close();
  right_.Close();
  started_ = false;
}

std::int32_t V4l2StereoSource::BuffersOutstanding() const {
  std::int32_t n = 0;
  if (left_.Fd() >= 0) n += left_.BufferCount() - left_.QueuedCount();
  if (!options_.side_by_side && right_.Fd() >= 0) {
    n += right_.BufferCount() - right_.QueuedCount();
  }
  return n;
}

}  // namespace swf::drivers
