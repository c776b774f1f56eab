// bench_hazard: one hazard update (dense stereo + fusion + analysis + site) on a simulated
// 1024x768 pair (EDL rig, crater field, 30 m), and our SGM against OpenCV 4.6 StereoSGBM
// (single thread) on the same pairs: the simulated pair at half resolution (512x384, scored
// against the renderer's exact disparity) and the Middlebury aloe pair at half resolution
// (641x555, scored against aloeGT.png). Counters: *_median_px (|error| of valid pixels),
// *_bad1 (fraction of valid pixels with |error| > 1 px), *_valid (valid / pixels with truth).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "swf/ground_cli/shared_dir.hpp"
#include "swf/hazard/hazard_mapper.hpp"
#include "swf/image_io/image_io.hpp"
#include "swf/sim/renderer.hpp"
#include "swf/sim/trajectory.hpp"

namespace {

using swf::frontend::GrayView;

// One stereo pair at full and half resolution with truth disparity (half-resolution pixels).
struct PairData {
  bool ok = false;
  int w = 0, h = 0;    // full
  int hw = 0, hh = 0;  // half
  std::vector<std::uint8_t> left, right, half_left, half_right;
  std::vector<float> half_truth;  // NaN / <= 0: no truth
  int min_d = 0, num_d = 0;       // half-resolution search range
  swf::estimator::StereoCamera<double> camera;
  swf::estimator::Pose<double> pose;
};

void Halve(PairData* p) {
  p->hw = (p->w + 1) / 2;
  p->hh = (p->h + 1) / 2;
  p->half_left.resize(static_cast<std::size_t>(p->hw) * p->hh);
  p->half_right.resize(p->half_left.size());
  swf::hazard::HalveImage(GrayView{p->left.data(), p->w, p->h, p->w}, p->half_left.data());
  swf::hazard::HalveImage(GrayView{p->right.data(), p->w, p->h, p->w}, p->half_right.data());
}

const PairData& SimPair() {
  static const PairData kData = [] {
    PairData p;
    swf::sim::Terrain terrain;
    swf::sim::Appearance appearance;
    swf::sim::Renderer renderer;
    if (terrain.Configure(swf::sim::TerrainPresetOptions(swf::sim::TerrainPreset::kCraterField,
                                                         1)) != swf::core::Status::kOk ||
        appearance.Configure(terrain, swf::sim::DefaultImagery(swf::ground_cli::SharedDir())) !=
            swf::core::Status::kOk ||
        renderer.Configure(swf::sim::RenderOptions{}) != swf::core::Status::kOk) {
      return p;
    }
    p.pose.R = swf::sim::NadirRotation(0.0);
    p.pose.t = {3.0, -2.0, terrain.HeightAt(3.0, -2.0) + 30.0};
    swf::sim::StereoImages images;
    if (renderer.Render(terrain, appearance, p.pose, 0, &images) != swf::core::Status::kOk) {
      return p;
    }
    p.w = images.width;
    p.h = images.height;
    p.left = images.left;
    p.right = images.right;
    p.camera = renderer.Camera();
    Halve(&p);
    p.half_truth.assign(static_cast<std::size_t>(p.hw) * p.hh, NAN);
    float lo = 1e9f;
    float hi = 0.0f;
    for (int y = 0; y < p.hh; ++y) {
      for (int x = 0; x < p.hw; ++x) {
        const float d = images.disparity_px[static_cast<std::size_t>(2 * y) * p.w + 2 * x];
        p.half_truth[static_cast<std::size_t>(y) * p.hw + x] = 0.5f * d;
        if (std::isfinite(d)) {
          lo = std::min(lo, 0.5f * d);
          hi = std::max(hi, 0.5f * d);
        }
      }
    }
    p.min_d = static_cast<int>(lo) - 4;
    p.num_d = ((static_cast<int>(hi) + 5 - p.min_d) + 15) / 16 * 16;  // OpenCV: multiple of 16
    p.ok = true;
    return p;
  }();
  return kData;
}

const PairData& AloePair() {
  static const PairData kData = [] {
    PairData p;
    const std::string dir = swf::ground_cli::SharedDir() + "/data/middlebury/";
    swf::image_io::GrayImage l;
    swf::image_io::GrayImage r;
    swf::image_io::GrayImage gt;
    std::string error;
    if (!swf::image_io::LoadGray(dir + "aloeL.jpg", &l, &error) ||
        !swf::image_io::LoadGray(dir + "aloeR.jpg", &r, &error) ||
        !swf::image_io::LoadChannel0(dir + "aloeGT.png", &gt, &error)) {
      return p;
    }
    p.w = l.width;
    p.h = l.height;
    p.left = l.pixels;
    p.right = r.pixels;
    Halve(&p);
    p.half_truth.assign(static_cast<std::size_t>(p.hw) * p.hh, NAN);
    for (int y = 0; y < p.hh; ++y) {
      for (int x = 0; x < p.hw; ++x) {
        const int g = gt.pixels[static_cast<std::size_t>(2 * y) * gt.width + 2 * x];
        if (g > 0) p.half_truth[static_cast<std::size_t>(y) * p.hw + x] = 0.5f * g;
      }
    }
    p.min_d = 0;
    p.num_d = 96;
    p.ok = true;
    return p;
  }();
  return kData;
}

// Scores a disparity map (invalid <= 0 or NaN) against truth, skipping the left strip where the
// search range leaves the image (both matchers leave it invalid).
void Score(const PairData& p, const float* disparity, benchmark::State& state,
           const std::string& prefix) {
  std::vector<double> err;
  int with_truth = 0;
  int bad = 0;
  for (int y = 0; y < p.hh; ++y) {
    for (int x = p.min_d + p.num_d; x < p.hw; ++x) {
      const float t = p.half_truth[static_cast<std::size_t>(y) * p.hw + x];
      if (!std::isfinite(t)) continue;
      ++with_truth;
      const float d = disparity[static_cast<std::size_t>(y) * p.hw + x];
      if (!(d > 0.0f)) continue;
      const double e = std::fabs(d - t);
      err.push_back(e);
      bad += e > 1.0;
    }
  }
  if (err.empty()) return;
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  state.counters[prefix + "_median_px"] = err[err.size() / 2];
  state.counters[prefix + "_bad1"] = static_cast<double>(bad) / err.size();
  state.counters[prefix + "_valid"] = static_cast<double>(err.size()) / with_truth;
}

void BmHazardUpdate(benchmark::State& state) {
  const PairData& p = SimPair();
  if (!p.ok) {
    state.SkipWithError("simulated pair failed (set SWF_SHARED_DIR)");
    return;
  }
  swf::hazard::HazardMapperOptions o;
  o.camera = p.camera;
  o.image_width = p.w;
  o.image_height = p.h;
  o.downsample = static_cast<int>(state.range(0));
  auto mapper = std::make_unique<swf::hazard::HazardMapper>();
  if (mapper->Configure(o) != swf::core::Status::kOk) {
    state.SkipWithError("configure failed");
    return;
  }
  swf::hazard::HazardFrame f;
  f.left = GrayView{p.left.data(), p.w, p.h, p.w};
  f.right = GrayView{p.right.data(), p.w, p.h, p.w};
  f.world_T_camera = p.pose;
  f.pose_covariance.diagonal() << 0.01, 0.01, 0.01, 1e-7, 1e-7, 1e-7;
  for (auto _ : state) {
    if (mapper->Update(f) != swf::core::Status::kOk) {
      state.SkipWithError("update failed");
      return;
    }
  }
  state.counters["num_disparities"] = mapper->Stats().num_disparities;
  state.counters["valid_pixels"] = mapper->Stats().valid_pixels;
  state.counters["grid_cells"] = mapper->GridCells();
}
BENCHMARK(BmHazardUpdate)->Arg(2)->Arg(4)->Unit(benchmark::kMillisecond);

void BmSgm(benchmark::State& state, const PairData& (*pair)(), const char* prefix) {
  const PairData& p = pair();
  if (!p.ok) {
    state.SkipWithError("data missing (set SWF_SHARED_DIR)");
    return;
  }
  auto sgm = std::make_unique<swf::hazard::SgmMatcher>();
  swf::hazard::SgmOptions o;
  o.max_width = p.hw;
  o.max_height = p.hh;
  o.max_disparities = p.num_d;
  o.paths = static_cast<int>(state.range(0));
  o.kernel = static_cast<swf::hazard::SgmKernel>(state.range(1));
  if (sgm->Configure(o) != swf::core::Status::kOk) {
    state.SkipWithError("configure failed");
    return;
  }
  const GrayView l{p.half_left.data(), p.hw, p.hh, p.hw};
  const GrayView r{p.half_right.data(), p.hw, p.hh, p.hw};
  for (auto _ : state) {
    if (sgm->Compute(l, r, p.min_d, p.num_d) != swf::core::Status::kOk) {
      state.SkipWithError("compute failed");
      return;
    }
  }
  Score(p, sgm->Disparity(), state, prefix);
  state.counters["num_disparities"] = p.num_d;
}

void BmOpenCv(benchmark::State& state, const PairData& (*pair)(), const char* prefix) {
  const PairData& p = pair();
  if (!p.ok) {
    state.SkipWithError("data missing (set SWF_SHARED_DIR)");
    return;
  }
  cv::setNumThreads(1);
  const int block = 5;
  auto sgbm = cv::StereoSGBM::create(p.min_d, p.num_d, block, 8 * block * block, 32 * block * block,
                                     1, 0, 10, 0, 0, static_cast<int>(state.range(0)));
  const cv::Mat l(p.hh, p.hw, CV_8UC1, const_cast<std::uint8_t*>(p.half_left.data()));
  const cv::Mat r(p.hh, p.hw, CV_8UC1, const_cast<std::uint8_t*>(p.half_right.data()));
  cv::Mat disp;
  for (auto _ : state) {
    sgbm->compute(l, r, disp);
    benchmark::DoNotOptimize(disp.data);
  }
  std::vector<float> d(static_cast<std::size_t>(p.hw) * p.hh);
  for (int y = 0; y < p.hh; ++y) {
    for (int x = 0; x < p.hw; ++x) {
      const short v = disp.at<short>(y, x);
      d[static_cast<std::size_t>(y) * p.hw + x] = v < p.min_d * 16 ? -1.0f : v / 16.0f;
    }
  }
  Score(p, d.data(), state, prefix);
}

void BmSgmSim(benchmark::State& s) { BmSgm(s, SimPair, "sim"); }
void BmOpenCvSgbmSim(benchmark::State& s) { BmOpenCv(s, SimPair, "sim"); }
void BmSgmAloe(benchmark::State& s) { BmSgm(s, AloePair, "aloe"); }
void BmOpenCvSgbmAloe(benchmark::State& s) { BmOpenCv(s, AloePair, "aloe"); }
// Ours: paths (8 or 4) x kernel (swf::hazard::SgmKernel: 0 = auto, 1 = portable 128-bit).
void SgmArgs(benchmark::internal::Benchmark* b) {
  b->ArgNames({"paths", "kernel"});
  for (int paths : {8, 4}) b->Args({paths, 0});
  b->Args({8, 1});
  b->Unit(benchmark::kMillisecond);
}
// range(0): cv::StereoSGBM mode (0 = MODE_SGBM, 5 paths; 1 = MODE_HH, 8 paths; 2 =
// MODE_SGBM_3WAY; 3 = MODE_HH4, 4 paths).
void OpenCvArgs(benchmark::internal::Benchmark* b) {
  b->ArgName("mode")->DenseRange(0, 3)->Unit(benchmark::kMillisecond);
}
BENCHMARK(BmSgmSim)->Apply(SgmArgs);
BENCHMARK(BmOpenCvSgbmSim)->Apply(OpenCvArgs);
BENCHMARK(BmSgmAloe)->Apply(SgmArgs);
BENCHMARK(BmOpenCvSgbmAloe)->Apply(OpenCvArgs);

}  // namespace

BENCHMARK_MAIN();
