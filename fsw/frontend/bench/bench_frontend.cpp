// Front-end timing on one 1024x768 stereo pair with ~300 tracked features (ARCHITECTURE.md
// budget: 10 ms on one core), stage by stage, and OpenCV 4.6 doing the same job on the same
// images (Harris goodFeaturesToTrack + pyramidal LK for the temporal track and for the stereo
// match), single-threaded. The images are an analytic band-limited texture moved by an exactly
// known subpixel shift and disparity, so both are also scored for accuracy (counters *_px).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <vector>

#include "swf/core/median.hpp"
#include "swf/frontend/frontend.hpp"
#include "swf/frontend/rectify.hpp"
#include "swf/frontend/synthetic_texture.hpp"

namespace {

using swf::frontend::GrayView;
using swf::frontend::synthetic::Texture;

constexpr int kW = 1024;
constexpr int kH = 768;
constexpr double kShiftX = 1.7;  // image motion between the two frames, pixels
constexpr double kShiftY = -0.9;
constexpr double kDisparity = 14.3;

struct Scene {
  cv::Mat prev_left;
  cv::Mat prev_right;
  cv::Mat cur_left;
  cv::Mat cur_right;
  Scene() {
    const Texture t(0);  // seed 0: the texture of every recorded result
    prev_left = Render([&](double x, double y) { return t(x, y); });
    prev_right = Render([&](double x, double y) { return t(x + kDisparity, y); });
    cur_left = Render([&](double x, double y) { return t(x - kShiftX, y - kShiftY); });
    cur_right =
        Render([&](double x, double y) { return t(x + kDisparity - kShiftX, y - kShiftY); });
  }
  template <typename F>
  static cv::Mat Render(F f) {
    cv::Mat m(kH, kW, CV_8UC1);
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        m.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(std::round(f(x, y)));
      }
    }
    return m;
  }
  static GrayView View(const cv::Mat& m) {
    return GrayView{m.ptr<std::uint8_t>(0), m.cols, m.rows, static_cast<int>(m.step[0])};
  }
};

const Scene& TheScene() {
  static const Scene kScene;
  return kScene;
}

swf::frontend::FrontendOptions Options() {
  swf::frontend::FrontendOptions o;
  o.camera.fx = o.camera.fy = 700.0;
  o.camera.cx = kW / 2.0;
  o.camera.cy = kH / 2.0;
  o.camera.baseline_m = 0.3;
  o.harris.bucket_cols = 20;
  o.harris.bucket_rows = 15;
  o.harris.max_per_bucket = 1;
  // Above the ~300 the buckets allow, so detection runs on every frame (the worst case: a
  // detector pass over the whole image) while ~300 landmarks are tracked.
  o.max_tracks = swf::frontend::kMaxTracks;
  return o;
}

// -1 for no values: an error no pair can have, plain in the report.
double Median(std::vector<double> v) {
  return v.empty() ? -1.0 : swf::core::MedianInPlace(v.data(), v.size());
}

// A Harris detector with the benchmark's bucketing.
std::unique_ptr<swf::frontend::HarrisDetector> MakeDetector() {
  auto detector = std::make_unique<swf::frontend::HarrisDetector>();
  (void)detector->Configure(Options().harris);
  return detector;
}

// Accuracy against the known shift and disparity, as SwfDetectTrackStereo and
// OpenCvDetectTrackStereo both score it.
void SetAccuracyCounters(benchmark::State& state, const std::vector<double>& flow_err,
                         const std::vector<double>& disp_err) {
  state.counters["tracked"] = static_cast<double>(flow_err.size());
  state.counters["stereo_matched"] = static_cast<double>(disp_err.size());
  state.counters["flow_median_err_px"] = Median(flow_err);
  state.counters["stereo_median_err_px"] = Median(disp_err);
}

// The whole-job benchmarks (the per-frame job, detect + track + stereo against OpenCV): in
// milliseconds, at least 3 s each.
void WholeJobTiming(benchmark::internal::Benchmark* b) {
  b->Unit(benchmark::kMillisecond)->MinTime(3.0);
}

// The whole per-frame job (detect + stereo + track + consistency) in steady state: the front end
// alternates between the two frames, so every call tracks ~300 landmarks and tops up detection.
void FrontendFrame(benchmark::State& state) {
  const Scene& s = TheScene();
  auto frontend = std::make_unique<swf::frontend::Frontend>();
  auto out = std::make_unique<swf::frontend::FrameOutput>();
  swf::frontend::FrontendOptions options = Options();
  options.detection_level = static_cast<int>(state.range(0));
  if (frontend->Configure(options) != swf::core::Status::kOk) state.SkipWithError("configure");
  const swf::frontend::StereoFrame a{Scene::View(s.prev_left), Scene::View(s.prev_right)};
  const swf::frontend::StereoFrame b{Scene::View(s.cur_left), Scene::View(s.cur_right)};
  (void)frontend->ProcessFrame(a, {}, out.get());  // initialises ~300 landmarks
  std::size_t measured = 0;
  std::size_t frames = 0;
  std::vector<double> disparity_errors;
  bool forward = true;
  for (auto _ : state) {
    const swf::frontend::StereoFrame& f = forward ? b : a;
    (void)frontend->ProcessFrame(f, {}, out.get());
    forward = !forward;
    measured += out->measurements.size();
    ++frames;
    benchmark::DoNotOptimize(out->measurements.data());
  }
  for (const auto& m : out->measurements) {
    disparity_errors.push_back(std::fabs(m.u_left - m.u_right - kDisparity));
  }
  state.counters["detected_per_frame"] = static_cast<double>(out->stats.corners);
  state.counters["tracked_per_frame"] =
      static_cast<double>(measured) / std::max<std::size_t>(1, frames);
  state.counters["stereo_median_err_px"] = Median(disparity_errors);
}
BENCHMARK(FrontendFrame)->Arg(0)->Arg(1)->ArgName("detection_level")->Apply(WholeJobTiming);

// Components on the same pair, for the breakdown.
void HarrisDetect(benchmark::State& state) {
  const Scene& s = TheScene();
  const auto detector = MakeDetector();
  auto corners = std::make_unique<swf::frontend::CornerList>();
  for (auto _ : state) {
    (void)detector->Detect(Scene::View(s.cur_left), nullptr, 0, corners.get());
    benchmark::DoNotOptimize(corners->data());
  }
  state.counters["corners"] = static_cast<double>(corners->size());
}
BENCHMARK(HarrisDetect)->Unit(benchmark::kMillisecond);

// Our components doing exactly the OpenCV job below: detect in the previous left image, track
// into the current left image, match current left -> current right. Accuracy against truth.
// brightness_offset = 1: LK solves for an additive offset per patch (the front end's default, for
// independently exposed cameras); 0: constant brightness, the model OpenCV's LK uses.
void SwfDetectTrackStereo(benchmark::State& state) {
  const bool offset = state.range(0) != 0;
  const Scene& s = TheScene();
  const auto detector = MakeDetector();
  auto corners = std::make_unique<swf::frontend::CornerList>();
  auto prev = std::make_unique<swf::frontend::Pyramid>();
  auto cur = std::make_unique<swf::frontend::Pyramid>();
  swf::frontend::PatchTracker tracker;
  swf::frontend::TrackerOptions tracker_options;
  tracker_options.brightness_offset = offset;
  (void)tracker.Configure(tracker_options);
  swf::frontend::StereoMatcher matcher;
  swf::frontend::StereoMatcherOptions stereo_options;
  stereo_options.brightness_offset = offset;
  (void)matcher.Configure(stereo_options);
  std::vector<double> flow_err;
  std::vector<double> disp_err;
  flow_err.reserve(1000);
  disp_err.reserve(1000);
  for (auto _ : state) {
    flow_err.clear();
    disp_err.clear();
    (void)detector->Detect(Scene::View(s.prev_left), nullptr, 0, corners.get());
    (void)prev->Build(Scene::View(s.prev_left), 3);
    (void)cur->Build(Scene::View(s.cur_left), 3);
    std::size_t n = 0;
    for (const auto& c : *corners) {
      if (n == 300) break;
      float x = c.x;
      float y = c.y;
      float q = 0.0f;
      if (!tracker.TrackFlow(*prev, *cur, c.x, c.y, &x, &y, &q)) continue;
      ++n;
      flow_err.push_back(std::hypot(x - c.x - kShiftX, y - c.y - kShiftY));
      swf::frontend::StereoMatch m;
      if (!matcher.Match(Scene::View(s.cur_left), Scene::View(s.cur_right),
                         static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y)), &m)) {
        continue;
      }
      float d = m.disparity;
      if (matcher.RefineDisparity(Scene::View(s.cur_left), Scene::View(s.cur_right), x, y, &d,
                                  &q)) {
        disp_err.push_back(std::fabs(d - kDisparity));
      }
    }
  }
  SetAccuracyCounters(state, flow_err, disp_err);
}
BENCHMARK(SwfDetectTrackStereo)
    ->Arg(1)
    ->Arg(0)
    ->ArgName("brightness_offset")
    ->Apply(WholeJobTiming);

void OpenCvDetectTrackStereo(benchmark::State& state) {
  cv::setNumThreads(1);
  const Scene& s = TheScene();
  std::vector<cv::Point2f> corners;
  std::vector<cv::Point2f> tracked;
  std::vector<cv::Point2f> right;
  std::vector<std::uint8_t> status_t;
  std::vector<std::uint8_t> status_s;
  std::vector<float> err;
  std::vector<double> flow_err;
  std::vector<double> disp_err;
  std::vector<double> disp_x_err;
  const cv::Size win(13, 13);  // the same window as ours (radius 6)
  const cv::TermCriteria term(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.005);
  for (auto _ : state) {
    cv::goodFeaturesToTrack(s.prev_left, corners, 300, 0.001, 8, cv::noArray(), 5, true, 0.04);
    cv::calcOpticalFlowPyrLK(s.prev_left, s.cur_left, corners, tracked, status_t, err, win, 2,
                             term);
    // Stereo with the same LK, started at zero disparity (OpenCV has no row-constrained SAD).
    right = tracked;
    cv::calcOpticalFlowPyrLK(s.cur_left, s.cur_right, tracked, right, status_s, err, win, 3, term,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
    benchmark::DoNotOptimize(right.data());
  }
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (!status_t[i]) continue;
    flow_err.push_back(
        std::hypot(tracked[i].x - corners[i].x - kShiftX, tracked[i].y - corners[i].y - kShiftY));
    if (status_s[i]) {
      disp_err.push_back(
          std::hypot(tracked[i].x - right[i].x - kDisparity, tracked[i].y - right[i].y));
      disp_x_err.push_back(std::fabs(tracked[i].x - right[i].x - kDisparity));
    }
  }
  SetAccuracyCounters(state, flow_err, disp_err);
  // Along the row only (OpenCV's stereo LK also moves in y; ours is constrained to the row).
  state.counters["stereo_x_median_err_px"] = Median(disp_x_err);
}
BENCHMARK(OpenCvDetectTrackStereo)->Apply(WholeJobTiming);

// Times the rectification of the scene's current pair.
void TimeRectify(benchmark::State& state, const swf::frontend::StereoRectifier& rectifier) {
  const Scene& s = TheScene();
  cv::Mat out_l(kH, kW, CV_8UC1);
  cv::Mat out_r(kH, kW, CV_8UC1);
  const swf::frontend::MutableGrayView ol{out_l.ptr<std::uint8_t>(0), kW, kH, kW};
  const swf::frontend::MutableGrayView orr{out_r.ptr<std::uint8_t>(0), kW, kH, kW};
  for (auto _ : state) {
    (void)rectifier.Rectify(Scene::View(s.cur_left), Scene::View(s.cur_right), ol, orr);
    benchmark::DoNotOptimize(out_l.data);
  }
}

// Rectification of a 1024x768 pair (reported separately; budget 1 ms). The argument forces a
// kernel: 0 = the one Configure picks for this CPU, then RemapKernel order (1 portable, 2 SSSE3,
// 3 AVX2, 4 NEON); all give the same bytes.
void RectifyPair(benchmark::State& state) {
  swf::frontend::CameraCalibration left;
  left.width = kW;
  left.height = kH;
  left.fx = left.fy = 700.0;
  left.cx = 511.0;
  left.cy = 383.0;
  left.k1 = -0.28;
  left.k2 = 0.07;
  left.p1 = 2e-4;
  left.p2 = 2e-5;
  swf::frontend::CameraCalibration right = left;
  right.body_T_camera.R =
      swf::estimator::ExpSO3<double>(swf::estimator::Vec3<double>(0.01, -0.02, 0.005));
  right.body_T_camera.t = swf::estimator::Vec3<double>(0.3, 0.002, -0.001);
  auto rectifier = std::make_unique<swf::frontend::StereoRectifier>();
  swf::frontend::RectifyOptions options;
  options.kernel = static_cast<swf::frontend::RemapKernel>(state.range(0));
  if (rectifier->Configure(left, right, options) != swf::core::Status::kOk) {
    state.SkipWithError("kernel not supported on this CPU");
    return;
  }
  constexpr const char* kKernelNames[] = {"auto", "portable", "ssse3", "avx2", "neon"};
  state.SetLabel(kKernelNames[static_cast<int>(rectifier->Kernel())]);
  TimeRectify(state, *rectifier);
  state.counters["table_error_px"] = rectifier->MaxTableErrorPx();
  state.counters["window_fraction"] = rectifier->WindowFraction();
}
BENCHMARK(RectifyPair)->Unit(benchmark::kMillisecond)->DenseRange(0, 3);

// An already rectified rig (the simulator's): the identity map is detected and rows are copied.
void RectifyIdentityPair(benchmark::State& state) {
  swf::frontend::CameraCalibration left;
  left.width = kW;
  left.height = kH;
  left.fx = left.fy = 700.0;
  left.cx = kW / 2.0;
  left.cy = kH / 2.0;
  swf::frontend::CameraCalibration right = left;
  right.body_T_camera.t = swf::estimator::Vec3<double>(0.3, 0.0, 0.0);
  auto rectifier = std::make_unique<swf::frontend::StereoRectifier>();
  if (rectifier->Configure(left, right, {}) != swf::core::Status::kOk || !rectifier->IsIdentity()) {
    state.SkipWithError("identity");
  }
  TimeRectify(state, *rectifier);
}
BENCHMARK(RectifyIdentityPair)->Unit(benchmark::kMillisecond);

// OpenCV's remap of the same pair with precomputed fixed-point maps, for reference.
void OpenCvRemapPair(benchmark::State& state) {
  cv::setNumThreads(1);
  const Scene& s = TheScene();
  const cv::Mat k = (cv::Mat_<double>(3, 3) << 700.0, 0, 511.0, 0, 700.0, 383.0, 0, 0, 1);
  const cv::Mat d = (cv::Mat_<double>(1, 4) << -0.28, 0.07, 2e-4, 2e-5);
  cv::Mat m1;
  cv::Mat m2;
  cv::initUndistortRectifyMap(k, d, cv::Mat(), k, cv::Size(kW, kH), CV_16SC2, m1, m2);
  cv::Mat out_l;
  cv::Mat out_r;
  for (auto _ : state) {
    cv::remap(s.cur_left, out_l, m1, m2, cv::INTER_LINEAR);
    cv::remap(s.cur_right, out_r, m1, m2, cv::INTER_LINEAR);
    benchmark::DoNotOptimize(out_l.data);
  }
}
BENCHMARK(OpenCvRemapPair)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
