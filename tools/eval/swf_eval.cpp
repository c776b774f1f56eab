// swf-eval: reruns the paper's experiments (section 4.2) on measurement-level synthetic scenes
// and on kitti-vo, and writes one JSON file per experiment plus gnuplot data under OUT/.
//   swf-eval paper OUT [--runs N] [--shared DIR]
// tools/run eval renders the plots and rebuilds docs/results.md from these files.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "../../estimator/test/synthetic_scene.hpp"
#include "kitti_vo.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"

namespace {

using swf::estimator::Mat3;
using swf::estimator::Mat6;
using swf::estimator::Pose;
using swf::estimator::SlidingWindowFilter;
using swf::estimator::StereoModel;
using swf::estimator::SwfMode;
using swf::estimator::SwfOptions;
using swf::estimator::Vec3;
using swf::estimator::testing::SceneOptions;
using swf::estimator::testing::SyntheticScene;

// Per-frame record of one run.
struct Trace {
  std::vector<double> mse_m2;     // mean squared landmark error of every landmark seen so far
  std::vector<double> update_ms;  // wall time of Update()
  std::vector<double> state_dim;  // 6 * poses + 3 * active landmarks
  double final_rms_m = 0.0;
};

template <typename Filter>
Trace RunFilter(const SyntheticScene& scene, SwfMode mode, int window, double q_t, double q_r,
                std::uint64_t seed) {
  auto swf = std::make_unique<Filter>();
  StereoModel<double> model;
  model.camera = scene.camera();
  SwfOptions options;
  options.mode = mode;
  options.window_size = window;
  options.first_pose_sigma_m = 1e-3;
  options.first_pose_sigma_rad = 1e-5;
  if (swf->Configure(model, options) != swf::core::Status::kOk) std::abort();
  Mat6<double> q_sqrt = Mat6<double>::Zero();
  q_sqrt.diagonal() << Vec3<double>::Constant(1 / q_t), Vec3<double>::Constant(1 / q_r);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / scene.options().sigma_px;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vec3<double>> estimate(scene.landmarks().size());
  std::vector<bool> known(scene.landmarks().size(), false);
  Trace trace;
  for (std::size_t j = 0; j < scene.frames().size(); ++j) {
    const auto& f = scene.frames()[j];
    if (j == 0) {
      (void)swf->AddPose(f.truth);
    } else {
      Pose<double> u = scene.frames()[j - 1].truth.Inverse() * f.truth;
      swf::estimator::Vec6<double> noise;
      for (int k = 0; k < 6; ++k) noise[k] = (k < 3 ? q_t : q_r) * gauss(rng);
      (void)swf->AddPoseWithMotion(u.Retract(noise), q_sqrt);
    }
    for (const auto& o : f.obs) (void)swf->AddObservation(o.id, o.z, r_sqrt);
    const auto start = std::chrono::steady_clock::now();
    (void)swf->Update();
    trace.update_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
    trace.state_dim.push_back(swf->Summary().state_dimension);
    for (const auto& r : swf->Retired()) {
      estimate[r.id] = r.position;
      known[r.id] = true;
    }
    swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int) {
      estimate[id] = p;
      known[id] = true;
    });
    double sum = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < estimate.size(); ++i) {
      if (!known[i]) continue;
      sum += (estimate[i] - scene.landmarks()[i]).squaredNorm();
      ++n;
    }
    trace.mse_m2.push_back(n > 0 ? sum / n : 0.0);
  }
  trace.final_rms_m = std::sqrt(trace.mse_m2.back());
  return trace;
}

// Capacities: windows up to 40 poses, 300 landmarks active, 200 per frame, 300 in the prior.
using Filter = SlidingWindowFilter<StereoModel<double>, 40, 300, 200, 160>;
using BigBatch = SlidingWindowFilter<StereoModel<double>, 160, 4000, 64, 1>;

// Cramer-Rao bound of the landmark MSE after m frames: trace of the landmark marginal
// covariances of the batch problem evaluated at the true state (noise-free measurements keep the
// solver at the truth).
std::vector<double> CramerRao(SceneOptions so) {
  const double sigma = so.sigma_px;
  so.sigma_px = 0.0;
  const SyntheticScene scene(so);
  std::vector<double> bound;
  auto swf = std::make_unique<Filter>();
  StereoModel<double> model;
  model.camera = scene.camera();
  SwfOptions options;
  options.mode = SwfMode::kBatch;
  options.robust = false;
  options.first_pose_sigma_m = 1e-3;
  options.first_pose_sigma_rad = 1e-5;
  (void)swf->Configure(model, options);
  Mat6<double> q_sqrt = Mat6<double>::Zero();
  q_sqrt.diagonal() << Vec3<double>::Constant(10.0), Vec3<double>::Constant(500.0);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / sigma;
  for (std::size_t j = 0; j < scene.frames().size(); ++j) {
    const auto& f = scene.frames()[j];
    if (j == 0) {
      (void)swf->AddPose(f.truth);
    } else {
      (void)swf->AddPoseWithMotion(scene.frames()[j - 1].truth.Inverse() * f.truth, q_sqrt);
    }
    for (const auto& o : f.obs) (void)swf->AddObservation(o.id, o.z, r_sqrt);
    (void)swf->Update();
    (void)swf->ComputeCovariances();
    double sum = 0.0;
    int n = 0;
    swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>&, int) {
      Mat3<double> c;
      if (swf->GetLandmarkCovariance(id, &c)) {
        sum += c.trace();
        ++n;
      }
    });
    bound.push_back(n > 0 ? sum / n : 0.0);
  }
  return bound;
}

struct Series {
  std::string name;
  std::vector<double> y;
};

// Averages a per-frame quantity over Monte Carlo runs (scene seed and motion-noise seed vary).
Series MonteCarlo(const std::string& name, SceneOptions so, int runs,
                  const std::function<Trace(const SyntheticScene&, std::uint64_t)>& run,
                  std::vector<double>* final_rms = nullptr) {
  Series s{name, {}};
  for (int r = 0; r < runs; ++r) {
    so.seed = 100 + static_cast<std::uint64_t>(r);
    const SyntheticScene scene(so);
    const Trace t = run(scene, 1000 + static_cast<std::uint64_t>(r));
    if (s.y.empty()) s.y.assign(t.mse_m2.size(), 0.0);
    for (std::size_t k = 0; k < t.mse_m2.size(); ++k) s.y[k] += t.mse_m2[k] / runs;
    if (final_rms != nullptr) final_rms->push_back(t.final_rms_m);
  }
  return s;
}

bool WriteExperiment(const std::string& out, const std::string& name, const std::string& x_label,
                     const std::vector<Series>& series, const std::string& extra_json) {
  std::ofstream dat(out + "/" + name + ".dat");
  std::ofstream json(out + "/" + name + ".json");
  if (!dat || !json) return false;
  dat << "# " << x_label;
  for (const Series& s : series) dat << " \"" << s.name << "\"";
  dat << "\n";
  const std::size_t n = series.empty() ? 0 : series[0].y.size();
  for (std::size_t k = 0; k < n; ++k) {
    dat << k + 1;
    for (const Series& s : series) dat << " " << (k < s.y.size() ? s.y[k] : NAN);
    dat << "\n";
  }
  json << "{\n  \"experiment\": \"" << name << "\",\n  \"x\": \"" << x_label << "\",\n";
  if (!extra_json.empty()) json << extra_json << ",\n";
  json << "  \"series\": {\n";
  for (std::size_t i = 0; i < series.size(); ++i) {
    json << "    \"" << series[i].name << "\": [";
    for (std::size_t k = 0; k < series[i].y.size(); ++k) json << (k ? ", " : "") << series[i].y[k];
    json << "]" << (i + 1 < series.size() ? "," : "") << "\n";
  }
  json << "  }\n}\n";
  std::printf("swf-eval: wrote %s/%s.json\n", out.c_str(), name.c_str());
  return static_cast<bool>(json);
}

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / v.size();
}
double Std(const std::vector<double>& v) {
  const double m = Mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return v.size() < 2 ? 0.0 : std::sqrt(s / (v.size() - 1));
}

int Usage() {
  std::fprintf(stderr, "usage: swf-eval paper OUT [--runs N] [--shared DIR]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || std::string(argv[1]) != "paper") return Usage();
  const std::string out = argv[2];
  int runs = 5;
  std::string shared = "../shared";
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--runs") {
      runs = std::atoi(argv[i + 1]);
    } else if (a == "--shared") {
      shared = argv[i + 1];
    } else {
      return Usage();
    }
  }
  if (runs < 1) return Usage();
  const double qt = 0.1;  // IMU-like relative motion: 10 cm, 2 mrad per frame (1 sigma)
  const double qr = 0.002;
  auto swf = [&](SwfMode mode, int k) {
    return [=](const SyntheticScene& s, std::uint64_t seed) {
      return RunFilter<Filter>(s, mode, k, qt, qr, seed);
    };
  };
  char buf[512];
  std::string md;  // docs/results.md, written from the same numbers as the JSON files
  auto add = [&md](const std::string& line) { md += line + "\n"; };
  add("# Results: the paper's experiments rerun");
  add("");
  add("Generated by `tools/run eval` (`swf-eval paper out/eval --runs " + std::to_string(runs) +
      "`); every number below is in a JSON file under `out/eval/` from the same run. Scenes are "
      "measurement-level (the estimator's synthetic scene: EDL rig, 1 m baseline, ~25 deg FOV, "
      "1024x768, 0.5 px noise, IMU-like motion input 10 cm / 2 mrad per frame). Errors are mean "
      "squared landmark error against truth over every landmark seen so far, averaged over the "
      "Monte Carlo runs.");
  add("");

  // Fig. 12: static cameras, 30 landmarks.
  {
    SceneOptions so;
    so.motion = SceneOptions::Motion::kStatic;
    so.start_altitude_m = 30.0;
    so.num_landmarks = 30;
    so.landmark_radius_m = 5.0;
    so.jitter_rad = 0.0;
    so.frames = 40;
    Series swf5 = MonteCarlo("SWF(5)", so, runs, swf(SwfMode::kSlidingWindow, 5));
    Series one_over_m{"1/m", {}};
    for (std::size_t k = 0; k < swf5.y.size(); ++k) one_over_m.y.push_back(swf5.y[0] / (k + 1));
    so.seed = 100;
    Series crlb{"CRLB", CramerRao(so)};
    std::snprintf(buf, sizeof(buf),
                  "  \"runs\": %d, \"mse_m2_at_40\": %.6g, \"crlb_m2_at_40\": %.6g", runs,
                  swf5.y.back(), crlb.y.back());
    WriteExperiment(out, "fig12_static", "frame", {swf5, one_over_m, crlb}, buf);
    add("## Fig. 12: static cameras, 30 landmarks");
    add("");
    add("![fig12](eval/fig12_static.png)");
    add("");
    std::snprintf(buf, sizeof(buf),
                  "SWF(5) MSE after 40 frames %.3g m^2; the 1/m curve from frame 1 gives %.3g m^2; "
                  "CRLB %.3g m^2. Paper: convergence close to 1/m with stationary cameras.",
                  swf5.y.back(), one_over_m.y.back(), crlb.y.back());
    add(buf);
    add("");
  }
  // Fig. 13: descent with 150 landmarks tracked throughout.
  {
    SceneOptions so;
    so.frames = 40;
    std::vector<Series> s;
    std::vector<double> rms_batch, rms_vo, rms_s3, rms_s10;
    s.push_back(MonteCarlo("batch", so, runs, swf(SwfMode::kBatch, 40), &rms_batch));
    s.push_back(MonteCarlo("SWF(3)", so, runs, swf(SwfMode::kSlidingWindow, 3), &rms_s3));
    s.push_back(MonteCarlo("SWF(4)", so, runs, swf(SwfMode::kSlidingWindow, 4)));
    s.push_back(MonteCarlo("SWF(5)", so, runs, swf(SwfMode::kSlidingWindow, 5)));
    s.push_back(MonteCarlo("SWF(10)", so, runs, swf(SwfMode::kSlidingWindow, 10), &rms_s10));
    s.push_back(MonteCarlo("VO(10)", so, runs, swf(SwfMode::kVisualOdometry, 10), &rms_vo));
    so.seed = 100;
    s.push_back(Series{"CRLB", CramerRao(so)});
    // The paper's claim: over 10 frames SWF error ~76% below VO, std ~3.5x smaller.
    std::snprintf(
        buf, sizeof(buf),
        "  \"runs\": %d, \"final_rms_m\": {\"batch\": %.6g, \"swf3\": %.6g, \"swf10\": %.6g, "
        "\"vo10\": %.6g},\n  \"swf10_error_below_vo10_percent\": %.3g,\n"
        "  \"vo10_std_over_swf10_std\": %.3g",
        runs, Mean(rms_batch), Mean(rms_s3), Mean(rms_s10), Mean(rms_vo),
        100.0 * (1.0 - Mean(rms_s10) / Mean(rms_vo)), Std(rms_vo) / std::max(Std(rms_s10), 1e-12));
    WriteExperiment(out, "fig13_descent", "frame", s, buf);
    add("## Fig. 13: descent, 150 landmarks tracked throughout (100 m to 41.5 m)");
    add("");
    add("![fig13](eval/fig13_descent.png)");
    add("");
    std::snprintf(
        buf, sizeof(buf),
        "Final landmark RMS: batch %.3f m, SWF(3) %.3f m, SWF(10) %.3f m, VO(10) %.3f m. "
        "Paper: 3-, 4-, 5-frame SWFs come close to batch. Ours: SWF(10) matches batch, "
        "short windows carry linearization error frozen into the prior from far altitude "
        "(with 0.01 px noise every window equals batch to 1e-5 m; see estimator/README.md).",
        Mean(rms_batch), Mean(rms_s3), Mean(rms_s10), Mean(rms_vo));
    add(buf);
    add("");
    std::snprintf(
        buf, sizeof(buf),
        "Paper claim (4.2.4): over 10 frames SWF error ~76%% below VO, standard deviation ~3.5x "
        "smaller. Ours, K=10 on this descent: %.0f%% below VO, standard deviation ratio %.2f over "
        "%d runs.",
        100.0 * (1.0 - Mean(rms_s10) / Mean(rms_vo)), Std(rms_vo) / std::max(Std(rms_s10), 1e-12),
        runs);
    add(buf);
    add("");
  }
  // Fig. 14: run time per frame and state-vector size.
  {
    SceneOptions so;
    so.motion = SceneOptions::Motion::kSideways;
    so.frames = 150;
    so.start_altitude_m = 50.0;
    so.step_m = 2.2;
    so.landmark_density_per_m2 = 0.055;
    so.seed = 7;
    const SyntheticScene scene(so);
    const Trace batch = RunFilter<BigBatch>(scene, SwfMode::kBatch, 150, qt, qr, 1);
    const Trace s10 = RunFilter<Filter>(scene, SwfMode::kSlidingWindow, 10, qt, qr, 1);
    const Trace s20 = RunFilter<Filter>(scene, SwfMode::kSlidingWindow, 20, qt, qr, 1);
    std::snprintf(buf, sizeof(buf), "  \"note\": \"wall-clock ms of Update() on the 2-core VM\"");
    WriteExperiment(
        out, "fig14a_runtime", "frame",
        {{"batch", batch.update_ms}, {"SWF(10)", s10.update_ms}, {"SWF(20)", s20.update_ms}}, buf);
    so.step_m = 4.4;  // ~5-frame tracks
    so.landmark_density_per_m2 = 0.08;
    so.frames = 100;
    const SyntheticScene scene_b(so);
    const Trace with = RunFilter<Filter>(scene_b, SwfMode::kSlidingWindow, 2, qt, qr, 1);
    const Trace without = RunFilter<BigBatch>(scene_b, SwfMode::kBatch, 100, qt, qr, 1);
    std::snprintf(buf, sizeof(buf),
                  "  \"mean_state_dim_swf2\": %.4g, \"final_state_dim_batch\": %.4g",
                  Mean(with.state_dim), without.state_dim.back());
    WriteExperiment(out, "fig14b_state_size", "frame",
                    {{"SWF(2) with marginalization", with.state_dim},
                     {"without marginalization", without.state_dim}},
                    buf);
    add("## Fig. 14: run time and state size");
    add("");
    add("![fig14a](eval/fig14a_runtime.png) ![fig14b](eval/fig14b_state_size.png)");
    add("");
    std::snprintf(
        buf, sizeof(buf),
        "Per-frame update (wall clock, shared VM): SWF(10) median-ish %.2f ms, SWF(20) %.2f ms at "
        "the last frame, batch %.1f ms at frame 150 and growing. State size with a 2-frame "
        "window: mean %.0f, without marginalization %.0f after 100 frames (paper: bounded vs "
        "growing). Benchmarks with medians: docs/benchmarks.md.",
        s10.update_ms.back(), s20.update_ms.back(), batch.update_ms.back(), Mean(with.state_dim),
        without.state_dim.back());
    add(buf);
    add("");
  }
  // Fig. 15: sideways motion, ~85% overlap, ~25 features per frame.
  {
    SceneOptions so;
    so.motion = SceneOptions::Motion::kSideways;
    so.start_altitude_m = 50.0;
    so.step_m = 3.3;
    so.landmark_density_per_m2 = 0.07;
    so.frames = 40;
    std::vector<Series> s;
    s.push_back(MonteCarlo("batch", so, runs, swf(SwfMode::kBatch, 40)));
    s.push_back(MonteCarlo("SWF(2)", so, runs, swf(SwfMode::kSlidingWindow, 2)));
    s.push_back(MonteCarlo("SWF(10)", so, runs, swf(SwfMode::kSlidingWindow, 10)));
    std::snprintf(buf, sizeof(buf), "  \"runs\": %d", runs);
    WriteExperiment(out, "fig15_sideways", "frame", s, buf);
    add("## Fig. 15: sideways motion, ~85% overlap");
    add("");
    add("![fig15](eval/fig15_sideways.png)");
    add("");
    std::snprintf(
        buf, sizeof(buf),
        "Final MSE: batch %.3g, SWF(2) %.3g, SWF(10) %.3g m^2. Paper: the 2-frame SWF suffers "
        "from early marginalization, the 10-frame SWF follows batch.",
        s[0].y.back(), s[1].y.back(), s[2].y.back());
    add(buf);
    add("");
  }
  // Fig. 17: VSDF against SWF with three active frames, every landmark in every frame.
  {
    SceneOptions so;
    so.frames = 40;
    so.num_landmarks = 100;
    std::vector<Series> s;
    s.push_back(MonteCarlo("SWF(3)", so, runs, swf(SwfMode::kSlidingWindow, 3)));
    s.push_back(MonteCarlo("VSDF(3)", so, runs, swf(SwfMode::kVsdf, 3)));
    s.push_back(MonteCarlo("batch", so, runs, swf(SwfMode::kBatch, 40)));
    std::snprintf(buf, sizeof(buf), "  \"runs\": %d", runs);
    WriteExperiment(out, "fig17_vsdf", "frame", s, buf);
    add("## Fig. 17: VSDF against SWF, 3 active frames");
    add("");
    add("![fig17](eval/fig17_vsdf.png)");
    add("");
    std::snprintf(
        buf, sizeof(buf),
        "Final MSE: SWF(3) %.3g, VSDF(3) %.3g, batch %.3g m^2. Paper: VSDF converges worse. "
        "Ours: this difference is not reproduced on our scenes (an open question, see the "
        "estimator issue).",
        s[0].y.back(), s[1].y.back(), s[2].y.back());
    add(buf);
    add("");
  }
  // Real data: kitti-vo batch against sliding windows on the same global cost.
  {
    swf::tools::KittiVoProblem problem;
    std::string error;
    const std::string dir = shared + "/data/kitti-vo/";
    if (!swf::tools::LoadKittiVo(dir + "VO_calibration.txt", dir + "VO_camera_poses_large.txt",
                                 dir + "VO_stereo_factors_large.txt", &problem, &error)) {
      std::fprintf(stderr, "swf-eval: %s\n", error.c_str());
      return 1;
    }
    const auto batch = swf::tools::SolveKittiVo(problem, 0);
    Series cost{"final cost", {}};
    Series dpos{"max position difference to batch (m)", {}};
    std::string list;
    for (int k : {2, 3, 5, 10, 20}) {
      const auto r = swf::tools::SolveKittiVo(problem, k);
      double worst = 0;
      for (std::size_t j = 0; j < r.poses.size(); ++j)
        worst = std::max(worst, (r.poses[j].t - batch.poses[j].t).norm());
      cost.y.push_back(r.final_cost);
      dpos.y.push_back(worst);
      std::snprintf(buf, sizeof(buf),
                    "%s{\"window\": %d, \"final_cost\": %.10g, \"max_position_diff_m\": %.6g}",
                    list.empty() ? "" : ", ", k, r.final_cost, worst);
      list += buf;
    }
    std::snprintf(buf, sizeof(buf),
                  "  \"initial_cost\": %.10g, \"batch_final_cost\": %.10g,\n  \"windows\": [",
                  batch.initial_cost, batch.final_cost);
    WriteExperiment(out, "kitti_windows", "window index (2,3,5,10,20)", {cost, dpos},
                    std::string(buf) + list + "]");
    add("## Real data: kitti-vo, batch against sliding windows");
    add("");
    std::snprintf(
        buf, sizeof(buf),
        "Initial cost %.6g, batch optimum %.6g (equal to Ceres's, tested). Windowed final costs "
        "on the same global cost, windows 2/3/5/10/20: %.6g / %.6g / %.6g / %.6g / %.6g; largest "
        "camera position difference to batch: %.3g / %.3g / %.3g / %.3g / %.3g m.",
        batch.initial_cost, batch.final_cost, cost.y[0], cost.y[1], cost.y[2], cost.y[3], cost.y[4],
        dpos.y[0], dpos.y[1], dpos.y[2], dpos.y[3], dpos.y[4]);
    add(buf);
    add("");
  }
  add("## Not yet evaluated");
  add("");
  add("Fig. 16 (MSE against track length and window), NEES consistency over 50 Monte Carlo runs, "
      "and EuRoC (`swf-eval euroc DIR`) are not implemented yet.");
  std::ofstream md_file(out + "/results.md");
  md_file << md;
  if (!md_file) {
    std::fprintf(stderr, "swf-eval: cannot write %s/results.md\n", out.c_str());
    return 1;
  }
  std::printf("swf-eval: wrote %s/results.md\n", out.c_str());
  return 0;
}
