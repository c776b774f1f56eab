// Integrity stress suite: "never wrong without saying so", on real frames.
//
// The 40 recorded EuRoC V1_01 stereo frames (20 Hz, a camera nearly at rest) are played as a
// ping-pong loop (forwards then backwards, so the image motion stays continuous) through the
// flight pipeline (swf::app::Pipeline: rectification, front end, Sliding Window Filter with the
// bounded constant-velocity model and no motion input, IntegrityMonitor; configured as swf-eval
// runs EuRoC, with the monitor's speed/step envelope set for this rig). Each case injects one
// fault after a clean warm-up and records, from the navigation output of every frame:
//   * detection: the first frame at or after the fault whose status is not VALID or whose
//     integrity flags (other than the informational NO_MOTION_INPUT) are set, in frames after
//     the fault's first frame, and the flags raised until recovery;
//   * the true position error (world = the first camera, as the pipeline's; the truth moved into
//     that frame exactly as swf-eval does) before, during and after the fault;
//   * recovery: frames from the end of the fault to the first VALID frame;
//   * misleading frames: VALID frames whose true horizontal or vertical error (split along the
//     world vertical) exceeds the HPL or VPL, and, as a second view, whose 3-D error exceeds
//     sqrt(HPL^2 + VPL^2).
// The assertions (bounds stated below, with margin over what was measured, docs/integrity.md):
// the error stays bounded, the fault is flagged or the estimate is unaffected, the output is
// VALID again within a bounded number of frames, and no VALID frame is beyond its protection
// level. The table of measured numbers is printed at the end of the run.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "euroc.hpp"
#include "sequence.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/estimator/integrity.hpp"
#include "swf/image_io/image_io.hpp"
#include "swf/testing/shared_dir.hpp"
#include "trajectory.hpp"

namespace swf::integrity_test {
namespace {

using swf::testing::SharedDir;

using eval::PoseD;
using eval::Vec3D;
using image_io::GrayImage;
namespace est = swf::estimator;

// ---- Bounds asserted for every case (see docs/integrity.md for what was measured). ----
// Largest true position error at any frame of any case (the camera moves < 3 mm: everything
// beyond a few millimetres is estimator error).
constexpr double kErrorBoundM = 0.05;
// A fault the monitor does not flag must leave the estimate within this of the truth, at every
// frame from the fault to the end of the case (about 4x the control's largest error, and the
// clean run's horizontal protection level).
constexpr double kUnaffectedM = 0.010;
// A flagged fault must be flagged within this many frames of its first frame.
constexpr int kMaxDetectionFrames = 3;
// VALID again within this many frames after the last faulty frame (recovery_frames = 5 after a
// restart, plus margin).
constexpr int kMaxRecoveryFrames = 15;
// Frames at the start of every case that may be DEGRADED while the window fills.
constexpr int kWarmupFrames = 20;
// The integrity monitor's envelope for the EuRoC rig (see Options()).
constexpr double kMaxSpeedMps = 2.0;
constexpr double kMaxStepM = 0.1;
// The fault starts here (1.5 s of clean frames before, the last 10 of them checked for alarms).
constexpr int kFaultStart = 30;

constexpr std::uint32_t kInformational = est::kFlagNoMotionInput;

// ---- The recorded frames, loaded once for every case. ----
struct Recorded {
  eval::EurocResult euroc;  // .sequence: calibration, rectified rig, truth per recorded frame
  std::vector<GrayImage> left;
  std::vector<GrayImage> right;
  std::int64_t interval_ns = 50'000'000;
  std::string error;
};

const Recorded& Data() {
  static const Recorded* data = [] {
    auto* d = new Recorded;
    if (!eval::LoadEuroc(SharedDir() + "/data/euroc-v101", eval::EurocOptions{}, &d->euroc,
                         &d->error)) {
      return d;
    }
    d->interval_ns = std::llround(d->euroc.frame_interval_s * 1e9);
    for (const eval::SequenceFrame& f : d->euroc.sequence.frames) {
      d->left.emplace_back();
      d->right.emplace_back();
      if (!image_io::LoadGray(f.left_path, &d->left.back(), &d->error) ||
          !image_io::LoadGray(f.right_path, &d->right.back(), &d->error)) {
        return d;
      }
    }
    return d;
  }();
  return *data;
}

// ---- Image faults (applied to the raw images, before the pipeline's rectification). ----
enum class Image {
  kClean,
  kBlack,        // both images 0
  kSaturated,    // both images 255
  kSwap,         // left and right exchanged
  kExposure,     // both images x 0.4
  kBlur,         // both images 9x9 box blur
  kTexturePoor,  // flat grey 128 with independent +-4 noise in each image
  kFewTracks,    // black except a 96 x 96 window at the centre
  kRepeated,     // a checkerboard (8 px period) over the centre, at a 15 px disparity
  kLookAlike,    // a third of the scene replaced by its own copy displaced 2 px per frame
  kShiftRight,   // the right image shifted 3 px left (every disparity +3 px)
};

const char* Name(Image i) {
  switch (i) {
    case Image::kClean: return "clean";
    case Image::kBlack: return "black";
    case Image::kSaturated: return "saturated";
    case Image::kSwap: return "swapped";
    case Image::kExposure: return "exposure x0.4";
    case Image::kBlur: return "blur 9x9";
    case Image::kTexturePoor: return "flat grey + noise";
    case Image::kFewTracks: return "96x96 window";
    case Image::kRepeated: return "checkerboard";
    case Image::kLookAlike: return "look-alike region sliding 2 px/frame";
    case Image::kShiftRight: return "right +3 px";
  }
  return "?";
}

std::uint32_t Lcg(std::uint32_t* state) {
  *state = *state * 1664525u + 1013904223u;
  return *state >> 8;
}

void Fill(GrayImage* im, std::uint8_t value) {
  std::fill(im->pixels.begin(), im->pixels.end(), value);
}

void BoxBlur(GrayImage* im, int radius) {
  const int w = im->width;
  const int h = im->height;
  std::vector<int> tmp(im->pixels.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int s = 0;
      int n = 0;
      for (int k = std::max(0, x - radius); k <= std::min(w - 1, x + radius); ++k, ++n)
        s += im->pixels[y * w + k];
      tmp[y * w + x] = s / n;
    }
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int s = 0;
      int n = 0;
      for (int k = std::max(0, y - radius); k <= std::min(h - 1, y + radius); ++k, ++n)
        s += tmp[k * w + x];
      im->pixels[y * w + x] = static_cast<std::uint8_t>(s / n);
    }
  }
}

// `k`: frames since the fault started (moving patterns).
void Apply(Image fault, int k, std::uint32_t seed, GrayImage* left, GrayImage* right) {
  const int w = left->width;
  const int h = left->height;
  switch (fault) {
    case Image::kClean: return;
    case Image::kBlack:
      Fill(left, 0);
      Fill(right, 0);
      return;
    case Image::kSaturated:
      Fill(left, 255);
      Fill(right, 255);
      return;
    case Image::kSwap: std::swap(left->pixels, right->pixels); return;
    case Image::kExposure:
      for (GrayImage* im : {left, right})
        for (std::uint8_t& p : im->pixels) p = static_cast<std::uint8_t>(std::lround(p * 0.4));
      return;
    case Image::kBlur:
      BoxBlur(left, 4);
      BoxBlur(right, 4);
      return;
    case Image::kTexturePoor: {
      std::uint32_t state = seed;
      for (GrayImage* im : {left, right})
        for (std::uint8_t& p : im->pixels) p = static_cast<std::uint8_t>(124 + Lcg(&state) % 9);
      return;
    }
    case Image::kFewTracks:
      for (GrayImage* im : {left, right}) {
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x)
            if (std::abs(x - w / 2) >= 48 || std::abs(y - h / 2) >= 48) im->pixels[y * w + x] = 0;
      }
      return;
    case Image::kRepeated: {
      // A periodic pattern at a plausible disparity: the true match at 15 px, aliases every
      // 8 px (7, 23, ...).
      constexpr int kDisparity = 15;
      for (int y = h / 4; y < 3 * h / 4; ++y) {
        for (int x = w / 4; x < 3 * w / 4; ++x) {
          const std::uint8_t v = ((x / 4 + y / 4) % 2) ? 200 : 50;
          left->pixels[y * w + x] = v;
          right->pixels[y * w + (x - kDisparity)] = v;
        }
      }
      return;
    }
    case Image::kLookAlike: {
      // The region x in [w/8, w/2), y in [h/4, 3h/4) of both images shows the scene's own
      // texture from 2 (k + 1) px further right: the tracked corners there find a perfect
      // look-alike that slides left 2 px per frame, with a consistent disparity (an object that
      // looks like the terrain and moves). About a third of the tracks are on it.
      const int shift = 2 * (k + 1);
      const GrayImage l0 = *left;
      const GrayImage r0 = *right;
      for (int y = h / 4; y < 3 * h / 4; ++y) {
        for (int x = w / 8; x < w / 2; ++x) {
          left->pixels[y * w + x] = l0.pixels[y * w + x + shift];
          right->pixels[y * w + x] = r0.pixels[y * w + x + shift];
        }
      }
      return;
    }
    case Image::kShiftRight: {
      const GrayImage r0 = *right;
      constexpr int kShift = 3;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          right->pixels[y * w + x] = r0.pixels[y * w + std::min(w - 1, x + kShift)];
      return;
    }
  }
}

// ---- A case: a schedule of frames fed to the pipeline, with one fault. ----
struct Feed {
  int source = 0;             // recorded frame shown (and whose truth is compared)
  std::int64_t stamp_ns = 0;  // timestamp handed to the pipeline
  Image image = Image::kClean;
  int fault_age = 0;  // frames since the fault's first frame
};

struct Case {
  std::string name;
  std::string fault;  // in words
  std::vector<Feed> frames;
  int fault_start = 0;  // index in frames of the first faulty frame
  int fault_end = 0;    // index of the first frame after the fault
  // Not empty: a requirement this case does not meet yet (docs/integrity.md, "Open"). The case
  // still runs and prints everything; it must still be flagged within kMaxDetectionFrames and
  // stay within kOpenErrorBoundM, and the requirements named here are reported, not asserted.
  std::string open;
};

// An open case's error bound: ten times the requirement, so a regression still fails.
constexpr double kOpenErrorBoundM = 0.5;

Case Open(Case c, const std::string& why) {
  c.open = why;
  return c;
}

// `total` ping-pong frames at the recorded interval.
std::vector<Feed> Clean(int total) {
  const Recorded& d = Data();
  const std::vector<int> order =
      eval::PingPong(static_cast<int>(d.euroc.sequence.frames.size()), total);
  std::vector<Feed> out;
  const std::int64_t t0 = d.euroc.sequence.frames.front().stamp_ns;
  for (int k = 0; k < total; ++k) {
    Feed f;
    f.source = order[k];
    f.stamp_ns = t0 + k * d.interval_ns;
    out.push_back(f);
  }
  return out;
}

constexpr int kAfter = 40;  // clean frames after every fault (2 s)

Case ImageFault(const std::string& name, Image image, int length, int after = kAfter) {
  Case c;
  c.name = name;
  c.fault = std::string(Name(image)) + " for " + std::to_string(length) + " frame" +
            (length > 1 ? "s" : "");
  c.frames = Clean(kFaultStart + length + after);
  c.fault_start = kFaultStart;
  c.fault_end = kFaultStart + length;
  for (int k = c.fault_start; k < c.fault_end; ++k) {
    c.frames[k].image = image;
    c.frames[k].fault_age = k - c.fault_start;
  }
  return c;
}

// The control: no fault, a long still period (`frames` frames of a camera at rest, no motion
// input: the constant-velocity model must hold still).
Case LongStill(int frames) {
  Case c;
  c.name = "LongStill";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "none: %.0f s at rest (control)", frames * 0.05);
  c.fault = buf;
  c.frames = Clean(frames);
  c.fault_start = kFaultStart;
  c.fault_end = kFaultStart + 1;
  return c;
}

// Frames `count` frames removed: the next frame arrives with the gap in its timestamp.
Case Dropped(int count) {
  Case c;
  c.name = count == 1 ? "DroppedFrame" : "DroppedFrames" + std::to_string(count);
  c.fault = std::to_string(count) + " frame" + (count > 1 ? "s" : "") + " dropped";
  c.frames = Clean(kFaultStart + count + kAfter);
  c.frames.erase(c.frames.begin() + kFaultStart, c.frames.begin() + kFaultStart + count);
  c.fault_start = kFaultStart;  // the frame after the gap
  c.fault_end = kFaultStart + 1;
  return c;
}

// The previous frame delivered again (same images), with the same or the next timestamp.
Case Duplicated(bool same_stamp) {
  const Recorded& d = Data();
  Case c;
  c.name = same_stamp ? "DuplicatedFrameSameStamp" : "DuplicatedFrameNewStamp";
  c.fault = std::string("previous pair delivered again, ") +
            (same_stamp ? "same timestamp" : "next timestamp");
  std::vector<Feed> base = Clean(kFaultStart + kAfter);
  Feed dup = base[kFaultStart - 1];
  base.insert(base.begin() + kFaultStart, dup);
  if (!same_stamp) {
    for (std::size_t k = kFaultStart; k < base.size(); ++k) base[k].stamp_ns += d.interval_ns;
  }
  c.frames = base;
  c.fault_start = kFaultStart;
  c.fault_end = kFaultStart + 1;
  return c;
}

// Every timestamp from the fault on shifted by `jump_s` (a clock step); the images continue.
Case TimestampJump(double jump_s) {
  Case c;
  c.name = jump_s > 0 ? "TimestampJumpForward" : "TimestampJumpBackward";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "timestamps step by %+.1f s", jump_s);
  c.fault = buf;
  c.frames = Clean(kFaultStart + kAfter);
  for (std::size_t k = kFaultStart; k < c.frames.size(); ++k)
    c.frames[k].stamp_ns += static_cast<std::int64_t>(std::llround(jump_s * 1e9));
  c.fault_start = kFaultStart;
  c.fault_end = kFaultStart + 1;
  return c;
}

// ---- Running a case. ----
struct FrameResult {
  int status = 2;
  std::uint32_t flags = 0;
  double hpl = 0.0;
  double vpl = 0.0;
  double error = 0.0;  // 3-D, m
  double error_h = 0.0;
  double error_v = 0.0;
  int tracked = 0;
  int estimate_status = 0;  // core::Status of Estimate()
  double sigma_m = 0.0;     // sqrt(trace) of the output's position covariance
  double sigma_rad = 0.0;   // sqrt(trace) of its rotation covariance
  double speed_mps = 0.0;   // |velocity| of the output
  std::int64_t gated = 0;   // cumulative: measurements gated before + rejected after fusion
  std::int64_t landmarks_rejected = 0;  // cumulative
  std::int64_t refused = 0;             // cumulative: new landmarks refused
  bool Alarm() const { return status != 0 || (flags & ~kInformational) != 0; }
  bool Misleading() const { return status == 0 && (error_h > hpl || error_v > vpl); }
  bool Misleading3d() const { return status == 0 && error > std::hypot(hpl, vpl); }
};

struct CaseResult {
  std::string name;
  std::string fault;
  int frames = 0;
  int fault_start = 0;
  int fault_end = 0;
  int detection = -1;         // frames from fault_start to the first alarm; -1 none
  std::uint32_t flags = 0;    // raised from fault_start to recovery (without informational)
  int worst_status = 0;       // over the same frames
  double error_before = 0.0;  // largest 3-D error before the fault
  double error_during = 0.0;
  double error_after = 0.0;
  int recovery = 0;  // frames from fault_end to the first VALID frame; -1 never
  int alarms_after_recovery = 0;
  int warmup_alarms = 0;  // alarms after kWarmupFrames and before the fault
  int misleading = 0;
  int misleading_3d = 0;
  int degraded_beyond_pl = 0;  // DEGRADED frames with the error beyond a protection level
  // Gate activity from the fault's first frame to 10 frames after its end (the response).
  std::int64_t gated = 0;
  std::int64_t landmarks_rejected = 0;
  std::int64_t refused = 0;
  double max_error_over_pl = 0.0;  // over VALID frames: max(e_h / HPL, e_v / VPL)
  std::int64_t restarts = 0;
  int valid = 0;
  int degraded = 0;
  int invalid = 0;
  double seconds = 0.0;
  std::vector<FrameResult> per_frame;
};

app::PipelineOptions Options(const eval::StereoSequence& s) {
  // As swf-eval runs EuRoC, with RunOptions' defaults.
  app::PipelineOptions o = eval::PipelineFor(s, eval::RunOptions{});
  // The monitor's envelope for this platform (a hand-carried / MAV rig indoors at 20 Hz; the
  // defaults, 300 m/s and 5 m per frame, are the lander's): faster than 2 m/s, or a solve moving
  // the newest pose more than 0.1 m from its prediction, is implausible here. Every other
  // integrity option is the default.
  o.integrity.max_speed_mps = kMaxSpeedMps;
  o.integrity.max_step_m = kMaxStepM;
  return o;  // initial_world_T_camera: identity, the estimate's world is the first camera
}

std::string FlagNames(std::uint32_t flags) {
  static const char* const kNames[est::kNumIntegrityFlags] = {
      "SOLVER_FAILED",   "IMPLAUSIBLE",   "DIVERGED",         "TOO_FEW_TRACKS",  "FEW_TRACKS",
      "RESIDUALS_HIGH",  "RESIDUAL_JUMP", "LARGE_STEP",       "COV_BAD",         "COV_LARGE",
      "DEGENERATE_GEOM", "NO_PARALLAX",   "GATE_SUSPENDED",   "NO_MOTION_INPUT", "RECOVERING",
      "REJECTED",        "TRACK_LOSS",    "MOTION_DISAGREES", "CAMERA_OUTAGE",   "MOTION_REJECTED"};
  std::string out;
  for (int b = 0; b < est::kNumIntegrityFlags; ++b) {
    if (((flags >> b) & 1u) == 0) continue;
    if (!out.empty()) out.push_back('+');
    out.append(kNames[b]);
  }
  return out.empty() ? "-" : out;
}

bool TruthMotion() {
  const char* v = std::getenv("SWF_INTEGRITY_TRUTH_MOTION");
  return v != nullptr && std::string(v) == "1";
}

CaseResult RunCase(const Case& c) {
  const Recorded& d = Data();
  const eval::StereoSequence& s = d.euroc.sequence;
  CaseResult r;
  r.name = c.name;
  r.fault = c.fault;
  r.frames = static_cast<int>(c.frames.size());
  r.fault_start = c.fault_start;
  r.fault_end = c.fault_end;
  auto pipeline = std::make_unique<app::Pipeline>();
  if (pipeline->Configure(Options(s)) != core::Status::kOk) {
    ADD_FAILURE() << c.name << ": the pipeline refused the configuration";
    return r;
  }
  const auto start = std::chrono::steady_clock::now();
  const PoseD world_T_truth0 = s.frames[c.frames.front().source].truth.Inverse();
  GrayImage left;
  GrayImage right;
  for (std::size_t j = 0; j < c.frames.size(); ++j) {
    const Feed& f = c.frames[j];
    left = d.left[f.source];
    right = d.right[f.source];
    Apply(f.image, f.fault_age, 12345u + static_cast<std::uint32_t>(j), &left, &right);
    app::PipelineFrame frame;
    frame.left = left.View();
    frame.right = right.View();
    frame.utime = f.stamp_ns / 1000;
    frame.seq = static_cast<std::int64_t>(j);
    core::Status st = pipeline->Rectify(frame);
    if (st == core::Status::kOk) st = pipeline->Track();
    if (st != core::Status::kOk) {
      ADD_FAILURE() << c.name << " frame " << j << ": the pipeline refused the images ("
                    << core::ToString(st) << ")";
      return r;
    }
    FrameResult fr;
    fr.tracked = pipeline->NumFeatures();
    // No motion input: the constant-velocity model (SWF_INTEGRITY_TRUTH_MOTION=1, diagnosis
    // only: the truth's frame-to-frame motion, as an IMU would give). A failed estimate is in
    // the output's status.
    PoseD truth_step;
    const bool with_truth = TruthMotion() && j > 0;
    if (with_truth)
      truth_step = s.frames[c.frames[j - 1].source].truth.Inverse() * s.frames[f.source].truth;
    fr.estimate_status = static_cast<int>(pipeline->Estimate(with_truth ? &truth_step : nullptr));
    app::NavOutput nav;
    pipeline->MakeNav(&nav);
    fr.status = nav.status;
    fr.flags = static_cast<std::uint32_t>(nav.integrity_flags);
    fr.hpl = nav.horizontal_protection_m;
    fr.vpl = nav.vertical_protection_m;
    fr.sigma_m =
        std::sqrt(std::max(0.0, nav.covariance[0] + nav.covariance[7] + nav.covariance[14]));
    fr.sigma_rad =
        std::sqrt(std::max(0.0, nav.covariance[21] + nav.covariance[28] + nav.covariance[35]));
    fr.speed_mps =
        std::hypot(nav.velocity_world_mps[0], nav.velocity_world_mps[1], nav.velocity_world_mps[2]);
    const app::IntegrityCounters& counters = pipeline->Integrity();
    fr.gated = counters.measurements_gated + counters.measurements_rejected;
    fr.landmarks_rejected = counters.landmarks_rejected;
    fr.refused = counters.new_landmarks_refused;
    const Vec3D truth = (world_T_truth0 * s.frames[f.source].truth).t;
    const Vec3D estimate(nav.position_world_m[0], nav.position_world_m[1], nav.position_world_m[2]);
    const Vec3D e = estimate - truth;
    fr.error = std::isfinite(e.norm()) ? e.norm() : 1e9;
    fr.error_v = std::fabs(e.dot(s.up_world));
    fr.error_h = (e - e.dot(s.up_world) * s.up_world).norm();
    if (!std::isfinite(fr.error_v) || !std::isfinite(fr.error_h)) fr.error_h = fr.error_v = 1e9;
    r.per_frame.push_back(fr);
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.restarts = pipeline->Integrity().restarts;

  const std::vector<FrameResult>& p = r.per_frame;
  const int n = static_cast<int>(p.size());
  for (int j = 0; j < n; ++j) {
    const FrameResult& fr = p[j];
    ++(fr.status == 0 ? r.valid : fr.status == 1 ? r.degraded : r.invalid);
    r.misleading += fr.Misleading();
    r.degraded_beyond_pl += fr.status == 1 && (fr.error_h > fr.hpl || fr.error_v > fr.vpl);
    r.misleading_3d += fr.Misleading3d();
    if (fr.status == 0) {
      r.max_error_over_pl = std::max({r.max_error_over_pl, fr.error_h / std::max(fr.hpl, 1e-12),
                                      fr.error_v / std::max(fr.vpl, 1e-12)});
    }
    double& slot = j < c.fault_start ? r.error_before
                   : j < c.fault_end ? r.error_during
                                     : r.error_after;
    slot = std::max(slot, fr.error);
    if (j >= kWarmupFrames && j < c.fault_start && fr.Alarm()) ++r.warmup_alarms;
  }
  // Detection: the first alarm from the fault's first frame to 10 frames after its end.
  for (int j = c.fault_start; j < std::min(n, c.fault_end + 10); ++j) {
    if (p[j].Alarm()) {
      r.detection = j - c.fault_start;
      break;
    }
  }
  // Recovery: the first VALID frame at or after the fault's end.
  r.recovery = -1;
  for (int j = c.fault_end; j < n; ++j) {
    if (p[j].status == 0 && !p[j].Alarm()) {
      r.recovery = j - c.fault_end;
      break;
    }
  }
  // Flags and worst status from the fault's first frame to recovery.
  const int until = r.recovery >= 0 ? c.fault_end + r.recovery : n;
  for (int j = c.fault_start; j < std::max(until, c.fault_end); ++j) {
    r.flags |= p[j].flags & ~kInformational;
    r.worst_status = std::max(r.worst_status, p[j].status);
  }
  if (r.recovery >= 0) {
    for (int j = until; j < n; ++j) r.alarms_after_recovery += p[j].Alarm();
  }
  const int g0 = c.fault_start - 1;
  const int g1 = std::min(n - 1, c.fault_end + 9);
  r.gated = p[g1].gated - p[g0].gated;
  r.landmarks_rejected = p[g1].landmarks_rejected - p[g0].landmarks_rejected;
  r.refused = p[g1].refused - p[g0].refused;
  return r;
}

const char* StatusName(int s) { return s == 0 ? "VALID" : s == 1 ? "DEGRADED" : "INVALID"; }

std::vector<CaseResult>& Results() {
  static std::vector<CaseResult> results;
  return results;
}

void Trace(const CaseResult& r) {
  const char* dir = std::getenv("SWF_INTEGRITY_TRACE");
  if (dir == nullptr) return;
  const std::string path = std::string(dir) + "/" + r.name + ".csv";
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return;
  std::fprintf(f,
               "frame,fault,status,flags,tracked,error_m,error_h_m,error_v_m,hpl_m,vpl_m,sigma_m,"
               "sigma_rad,speed_mps,gated,landmarks_rejected,refused\n");
  for (std::size_t j = 0; j < r.per_frame.size(); ++j) {
    const FrameResult& fr = r.per_frame[j];
    const bool fault = static_cast<int>(j) >= r.fault_start && static_cast<int>(j) < r.fault_end;
    std::fprintf(f, "%zu,%d,%d,%s,%d,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f,%.5f,%.4f,%lld,%lld,%lld\n", j,
                 fault ? 1 : 0, fr.status, FlagNames(fr.flags).c_str(), fr.tracked, fr.error,
                 fr.error_h, fr.error_v, fr.hpl, fr.vpl, fr.sigma_m, fr.sigma_rad, fr.speed_mps,
                 static_cast<long long>(fr.gated), static_cast<long long>(fr.landmarks_rejected),
                 static_cast<long long>(fr.refused));
  }
  std::fclose(f);
}

class IntegrityStress : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { Data(); }

  static void TearDownTestSuite() {
    std::printf(
        "\n| case | fault | frames (fault) | detection (frames) | worst status | flags raised | "
        "gated / lm rejected / refused | error before / during / after (mm) | recovery "
        "(frames) | alarms after | restarts | VALID/DEG/INV | misleading (h,v / 3-D) | max err/PL "
        "| "
        "DEG beyond PL | s |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const CaseResult& r : Results()) {
      std::printf(
          "| %s | %s | %d (%d-%d) | %s | %s | %s | %lld / %lld / %lld | %.1f / %.1f / %.1f | %s | "
          "%d | %lld | %d/%d/%d | %d / %d | %.2f | %d | %.1f |\n",
          r.name.c_str(), r.fault.c_str(), r.frames, r.fault_start, r.fault_end - 1,
          r.detection < 0 ? "none" : std::to_string(r.detection).c_str(),
          StatusName(r.worst_status), FlagNames(r.flags).c_str(), static_cast<long long>(r.gated),
          static_cast<long long>(r.landmarks_rejected), static_cast<long long>(r.refused),
          1e3 * r.error_before, 1e3 * r.error_during, 1e3 * r.error_after,
          r.recovery < 0 ? "never" : std::to_string(r.recovery).c_str(), r.alarms_after_recovery,
          static_cast<long long>(r.restarts), r.valid, r.degraded, r.invalid, r.misleading,
          r.misleading_3d, r.max_error_over_pl, r.degraded_beyond_pl, r.seconds);
    }
    std::fflush(stdout);
  }

  // Runs the case and checks what must hold for every fault.
  static CaseResult Check(const Case& c) {
    const Recorded& d = Data();
    EXPECT_TRUE(d.error.empty()) << d.error;
    if (!d.error.empty()) return CaseResult{};
    CaseResult r = RunCase(c);
    Trace(r);
    Results().push_back(r);
    std::printf(
        "%s: %s; detection %d, flags %s, worst %s, error %.1f/%.1f/%.1f mm, recovery %d, "
        "restarts %lld, misleading %d (3-D %d), max err/PL %.2f, %.1f s\n",
        r.name.c_str(), r.fault.c_str(), r.detection, FlagNames(r.flags).c_str(),
        StatusName(r.worst_status), 1e3 * r.error_before, 1e3 * r.error_during, 1e3 * r.error_after,
        r.recovery, static_cast<long long>(r.restarts), r.misleading, r.misleading_3d,
        r.max_error_over_pl, r.seconds);
    const double worst = std::max({r.error_before, r.error_during, r.error_after});
    const bool detected = r.detection >= 0 && r.detection <= kMaxDetectionFrames;
    if (!c.open.empty()) {
      std::printf("%s: OPEN: %s\n", c.name.c_str(), c.open.c_str());
      EXPECT_TRUE(detected) << c.name << ": an open case must at least be flagged";
      EXPECT_LE(worst, kOpenErrorBoundM) << c.name << ": worse than when it was opened";
      EXPECT_EQ(r.warmup_alarms, 0) << c.name << ": alarms on clean frames before the fault";
      return r;
    }
    EXPECT_LE(worst, kErrorBoundM) << c.name << ": the true position error is not bounded";
    const bool unaffected = std::max(r.error_during, r.error_after) <= kUnaffectedM;
    EXPECT_TRUE(detected || unaffected)
        << c.name << ": the fault was not flagged within " << kMaxDetectionFrames
        << " frames (detection " << r.detection << ") and moved the estimate "
        << 1e3 * std::max(r.error_during, r.error_after) << " mm from the truth (tolerance "
        << 1e3 * kUnaffectedM << " mm)";
    EXPECT_GE(r.recovery, 0) << c.name << ": never VALID again after the fault";
    EXPECT_LE(r.recovery, kMaxRecoveryFrames) << c.name << ": slow recovery";
    EXPECT_EQ(r.misleading, 0) << c.name << ": VALID frames beyond their protection level";
    EXPECT_EQ(r.misleading_3d, 0) << c.name
                                  << ": VALID frames with the 3-D error beyond "
                                     "sqrt(HPL^2 + VPL^2)";
    EXPECT_EQ(r.warmup_alarms, 0) << c.name << ": alarms on clean frames before the fault";
    return r;
  }
};

// GIVEN the clean loop for 15 s at rest WHEN nothing is injected THEN the output is VALID after
// the warm-up, within the bound, and never beyond its protection level: the constant-velocity
// model does not run away (the control for every case below).
TEST_F(IntegrityStress, LongStill) {
  const CaseResult r = Check(LongStill(300));
  EXPECT_EQ(r.detection, -1) << "an alarm on clean frames";
}

// GIVEN the loop WHEN one frame (or five) never arrives (the next one comes with the gap in its
// timestamp) THEN the estimate is unaffected (the constant-velocity model spans the gap).
TEST_F(IntegrityStress, DroppedFrame) { Check(Dropped(1)); }
TEST_F(IntegrityStress, DroppedFrames5) { Check(Dropped(5)); }

// GIVEN the loop WHEN the previous stereo pair is delivered again, with its own timestamp
// repeated (dt = 0) or with the next one THEN the estimate is unaffected.
TEST_F(IntegrityStress, DuplicatedFrameSameStamp) { Check(Duplicated(true)); }
TEST_F(IntegrityStress, DuplicatedFrameNewStamp) { Check(Duplicated(false)); }

// GIVEN the loop WHEN the clock steps by +5 s or -1 s (images continuous) THEN the estimate is
// unaffected (the still scene is held, speeds are not integrated over the step).
TEST_F(IntegrityStress, TimestampJumpForward) { Check(TimestampJump(5.0)); }
TEST_F(IntegrityStress, TimestampJumpBackward) { Check(TimestampJump(-1.0)); }

// GIVEN the loop WHEN one pair is all black / all 255 THEN the frame is flagged and the
// output VALID again on the next frame, within the bound.
TEST_F(IntegrityStress, BlackPair) { Check(ImageFault("BlackPair", Image::kBlack, 1)); }
TEST_F(IntegrityStress, SaturatedPair) { Check(ImageFault("SaturatedPair", Image::kSaturated, 1)); }

// GIVEN the loop WHEN one pair arrives with left and right exchanged THEN it is flagged
// within 3 frames, the error stays bounded and no VALID frame is beyond its protection level.
TEST_F(IntegrityStress, SwappedPair) {
  Check(Open(ImageFault("SwappedPair", Image::kSwap, 1),
             "error after the two restarts 0.40 m > 50 mm: the restart re-initializes every "
             "landmark from the next frame and keeps an offset"));
}

// GIVEN the loop WHEN 10 pairs are 0.4x as bright (exposure jump down and back up) / box
// blurred 9x9 THEN flagged or unaffected, bounded, never VALID beyond the protection level.
TEST_F(IntegrityStress, ExposureJump) {
  Check(Open(ImageFault("ExposureJump", Image::kExposure, 10),
             "flagged (REJECTED, TRACK_LOSS) but the filter keeps the biased 24-36 mm and is "
             "VALID again after recovery_frames with protection levels of ~15 mm"));
}
TEST_F(IntegrityStress, Blur) {
  Check(Open(ImageFault("Blur", Image::kBlur, 10),
             "flagged, but VALID again after recovery_frames with the error up to 1.1x its "
             "protection level"));
}

// GIVEN the loop WHEN 10 pairs are texture-poor (flat grey with independent noise) / show
// only a 96x96 window (few tracks, bunched) THEN flagged from the first frame, bounded, VALID
// again within the recovery bound.
TEST_F(IntegrityStress, TexturePoor) {
  Check(Open(ImageFault("TexturePoor", Image::kTexturePoor, 10),
             "no VALID recovery: the rotation sigma grown while blind stays above the 0.1 rad "
             "envelope (DEGRADED, COVARIANCE_LARGE) for the rest of the run"));
}
TEST_F(IntegrityStress, FewTracks) {
  Check(Open(ImageFault("FewTracks", Image::kFewTracks, 10),
             "INVALID during the fault, but the error reaches 97 mm after it"));
}

// GIVEN the loop WHEN the centre of both images shows a checkerboard (period 8 px, at a 15 px
// disparity: stereo aliases 8 px apart) for 10 pairs THEN flagged or unaffected.
TEST_F(IntegrityStress, RepeatedTexture) {
  Check(ImageFault("RepeatedTexture", Image::kRepeated, 10));
}

// GIVEN the loop WHEN a third of the scene is replaced by its own look-alike sliding 2 px per
// frame for 10 pairs (consistent stereo, wrong motion) THEN flagged or unaffected, and never
// VALID beyond the protection level.
TEST_F(IntegrityStress, LookAlikeRegion) {
  Check(Open(ImageFault("LookAlikeRegion", Image::kLookAlike, 10),
             "flagged at frame 1, 127 mm error during it, one VALID frame beyond its protection "
             "level (3.9x)"));
}

// GIVEN the loop WHEN the right image of one pair is shifted by 3 px (every disparity +3 px:
// a look-alike match for every feature) THEN flagged or unaffected.
TEST_F(IntegrityStress, RightImageShifted) {
  Check(ImageFault("RightImageShifted", Image::kShiftRight, 1));
}

// GIVEN the loop WHEN the cameras go black for 2 s (40 frames) THEN INVALID during it, the
// constant-velocity model does not run away, VALID again within the recovery bound, and the
// error bounded for the 3 s after.
TEST_F(IntegrityStress, Blackout2s) {
  Check(Open(ImageFault("Blackout2s", Image::kBlack, 40, 60),
             "INVALID during it and bounded (2.5 mm), but no VALID recovery: the rotation sigma "
             "grown while blind stays above the 0.1 rad envelope"));
}

}  // namespace
}  // namespace swf::integrity_test
