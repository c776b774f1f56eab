// swf-eval: reruns the paper's experiments (section 4.2) on measurement-level synthetic scenes
// and on kitti-vo, and writes one JSON file per experiment plus gnuplot data under OUT/.
//   swf-eval paper OUT [--runs N] [--shared DIR]
// The real-data commands (euroc, kitti) are in commands.cpp.
// tools/run eval renders the plots and rebuilds docs/results.md from these files.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "experiment_file.hpp"
#include "experiments.hpp"
#include "json.hpp"
#include "kitti.hpp"
#include "kitti_vo.hpp"
#include "run_filter.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "swf/evaluation/statistics.hpp"
#include "swf/frontend/config.hpp"
#include "swf/ground_cli/ground_cli.hpp"

namespace {

using swf::estimator::Mat3;
using swf::estimator::Mat6;
using swf::estimator::Pose;
using swf::estimator::SlidingWindowFilter;
using swf::estimator::StereoModel;
using swf::estimator::SwfMode;
using swf::estimator::SwfOptions;
using swf::estimator::Vec3;
using swf::eval::BigBatch;
using swf::eval::Filter;
using swf::eval::InverseDepthFilter;
using swf::eval::Json;
using swf::eval::kMotionSigmaM;
using swf::eval::kMotionSigmaRad;
using swf::eval::Numbers;
using swf::eval::Output;
using swf::eval::RunFilter;
using swf::eval::Series;
using swf::eval::SetNumber;
using swf::eval::SetNumbers;
using swf::eval::Trace;
using swf::eval::WriteExperiment;
using Figure = swf::eval::Figure;
using swf::evaluation::Mean;
using swf::evaluation::Median;
using swf::evaluation::SampleStd;
using swf::scene::SceneOptions;
using swf::scene::SyntheticScene;

// The y axis of the landmark-error figures: the MSE over every landmark seen so far, averaged
// over the Monte Carlo runs.
constexpr const char* kLandmarkMse = "landmark mean squared error (m^2)";

// "1 run", "5 runs": how many Monte Carlo runs a figure averages.
std::string RunsText(int runs) { return std::to_string(runs) + (runs == 1 ? " run" : " runs"); }

// The batch problem of a scene at the true state (noise-free measurements keep the solver at the
// truth), its marginal covariances computed after every frame: visit(filter, frame) reads them.
// Its landmark covariances are the Cramer-Rao bound (eq. 11).
template <typename Visit>
void AtTruth(SceneOptions so, Visit visit) {
  const double sigma = so.sigma_px;
  so.sigma_px = 0.0;
  const SyntheticScene scene(so);
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
    visit(*swf, j);
  }
}

// Cramer-Rao bound of the landmark MSE after m frames: the trace of the landmark marginal
// covariances at the truth, averaged over the landmarks.
std::vector<double> CramerRao(const SceneOptions& so) {
  std::vector<double> bound;
  AtTruth(so, [&bound](const Filter& swf, std::size_t) {
    double sum = 0.0;
    int n = 0;
    swf.ForEachLandmark([&](std::int64_t id, const Vec3<double>&, int) {
      Mat3<double> c;
      if (swf.GetLandmarkCovariance(id, &c)) {
        sum += c.trace();
        ++n;
      }
    });
    bound.push_back(n > 0 ? sum / n : 0.0);
  });
  return bound;
}

// Averages a per-frame quantity over Monte Carlo runs (scene seed and motion-noise seed vary).
// Optionally collects each run's final RMS, final MSE, and failed updates (summed).
Series MonteCarlo(const std::string& name, SceneOptions so, int runs,
                  const std::function<Trace(const SyntheticScene&, std::uint64_t)>& run,
                  std::vector<double>* final_rms = nullptr,
                  std::vector<double>* final_mse = nullptr, int* failed_updates = nullptr,
                  Series* median = nullptr) {
  std::vector<std::vector<double>> per_run;
  Series s{name, {}};
  for (int r = 0; r < runs; ++r) {
    so.seed = 100 + static_cast<std::uint64_t>(r);
    const SyntheticScene scene(so);
    const Trace t = run(scene, 1000 + static_cast<std::uint64_t>(r));
    if (s.y.empty()) s.y.assign(t.mse_m2.size(), 0.0);
    for (std::size_t k = 0; k < t.mse_m2.size(); ++k) s.y[k] += t.mse_m2[k] / runs;
    if (final_rms != nullptr) final_rms->push_back(t.rms_m);
    if (final_mse != nullptr) final_mse->push_back(t.mse_m2.back());
    if (failed_updates != nullptr) *failed_updates += t.failures;
    per_run.push_back(t.mse_m2);
  }
  if (median != nullptr) {
    *median = Series{name + ", median", {}};
    for (std::size_t k = 0; k < s.y.size(); ++k) {
      std::vector<double> at_k;
      for (const auto& run_mse : per_run)
        if (k < run_mse.size()) at_k.push_back(run_mse[k]);
      median->y.push_back(Median(at_k));
    }
  }
  return s;
}

// "consistent" / "overconfident" / "conservative" from the frame-averaged NEES against the
// 95% band of a single frame's run average.
std::string NeesVerdict(const char* what, double mean, double dof, double lower, double upper,
                        double fraction_inside) {
  char text[512];
  if (mean >= lower && mean <= upper) {
    std::snprintf(text, sizeof(text),
                  "%s NEES averages %.2f (expected %.0f, 95%% band [%.2f, %.2f]): consistent; "
                  "%.0f%% of frames inside the band",
                  what, mean, dof, lower, upper, 100.0 * fraction_inside);
  } else if (mean > upper) {
    std::snprintf(text, sizeof(text),
                  "%s NEES averages %.2f (expected %.0f, 95%% band [%.2f, %.2f]): overconfident, "
                  "the errors are %.2fx larger in variance (%.2fx in standard deviation) than the "
                  "covariance states; %.0f%% of frames inside the band",
                  what, mean, dof, lower, upper, mean / dof, std::sqrt(mean / dof),
                  100.0 * fraction_inside);
  } else {
    std::snprintf(text, sizeof(text),
                  "%s NEES averages %.2f (expected %.0f, 95%% band [%.2f, %.2f]): conservative, "
                  "the covariance is %.2fx larger in variance than the errors; %.0f%% of frames "
                  "inside the band",
                  what, mean, dof, lower, upper, dof / mean, 100.0 * fraction_inside);
  }
  return text;
}

// A line of docs/results.md.
void AddLine(std::string* md, const std::string& line) { *md += line + "\n"; }

// A paragraph (or heading) of docs/results.md: its line and the blank line that ends it.
void AddParagraph(std::string* md, const std::string& text) {
  AddLine(md, text);
  AddLine(md, "");
}

// A figure's section of docs/results.md: its heading and its plots, each a paragraph.
void AddFigure(std::string* md, const std::string& heading, const std::string& plots) {
  AddParagraph(md, heading);
  AddParagraph(md, plots);
}

// The filter in `mode` with a window of k poses, as a Monte Carlo run.
std::function<Trace(const SyntheticScene&, std::uint64_t)> SwfRun(SwfMode mode, int k) {
  return [=](const SyntheticScene& s, std::uint64_t seed) {
    return RunFilter<Filter>(s, mode, k, seed);
  };
}

// Consistency: NEES over Monte Carlo runs.
bool AddNees(const Output& out, int runs, std::string* md) {
  using swf::eval::NeesOptions;
  using swf::eval::NeesResult;
  // The Fig. 15 scene (sideways at 50 m, ~25 features per frame, landmarks entering and leaving)
  // exercises pose and landmark marginalization; the descent scene with 40 landmarks is the EDL
  // case.
  const SceneOptions sideways = swf::scene::Fig15Sideways();
  SceneOptions descent;
  descent.frames = 40;
  descent.num_landmarks = 40;
  SceneOptions descent_low = descent;  // same descent, 3.3x closer: 3.3x the disparity
  descent_low.start_altitude_m = 30.0;
  descent_low.step_m = 0.5;
  struct Config {
    std::string name;
    SceneOptions scene;
    SwfMode mode;
    int window;
    int hold_sightings = 0;
    double hold_depth_precision = 0.0;
  };
  // The remedy for the descent's overconfidence (docs/integrity.md): the window holds its oldest
  // pose while that pose sees a tracked landmark with fewer sightings than this.
  constexpr int kHoldSightings = 25;
  // ... or while it sees one whose depth its sightings know to worse than this relative 1-sigma
  // (`SwfOptions::hold_depth_precision`): 0.3 % held the whole descent, 0.7 % left SWF(5) at 1.5x.
  constexpr double kHoldDepth = 0.005;
  const std::vector<Config> configs = {
      {"SWF(2) sideways", sideways, SwfMode::kSlidingWindow, 2},
      {"SWF(5) sideways", sideways, SwfMode::kSlidingWindow, 5},
      {"SWF(10) sideways", sideways, SwfMode::kSlidingWindow, 10},
      {"SWF(5) descent", descent, SwfMode::kSlidingWindow, 5},
      {"SWF(10) descent", descent, SwfMode::kSlidingWindow, 10},
      {"batch descent", descent, SwfMode::kBatch, 40},
      {"SWF(5) descent, held", descent, SwfMode::kSlidingWindow, 5, kHoldSightings},
      {"SWF(10) descent, held", descent, SwfMode::kSlidingWindow, 10, kHoldSightings},
      {"SWF(5) descent, held by depth", descent, SwfMode::kSlidingWindow, 5, 0, kHoldDepth},
      {"SWF(10) descent, held by depth", descent, SwfMode::kSlidingWindow, 10, 0, kHoldDepth},
      {"SWF(5) descent from 30 m", descent_low, SwfMode::kSlidingWindow, 5},
      {"SWF(5) descent from 30 m, held", descent_low, SwfMode::kSlidingWindow, 5, kHoldSightings},
      {"SWF(5) descent from 30 m, held by depth", descent_low, SwfMode::kSlidingWindow, 5, 0,
       kHoldDepth},
      {"SWF(2) sideways, held", sideways, SwfMode::kSlidingWindow, 2, kHoldSightings},
      {"SWF(2) sideways, held by depth", sideways, SwfMode::kSlidingWindow, 2, 0, kHoldDepth},
      // Fig. 17's question asked of the covariances: the same filters with eq. 12's
      // block-diagonal marginalization.
      {"SWF(3) descent from 30 m", descent_low, SwfMode::kSlidingWindow, 3},
      {"VSDF(3) descent from 30 m", descent_low, SwfMode::kVsdf, 3},
      {"VSDF(5) descent", descent, SwfMode::kVsdf, 5},
  };
  std::vector<NeesResult> results;
  for (const Config& c : configs) {
    NeesOptions o;
    o.scene = c.scene;
    o.mode = c.mode;
    o.window = c.window;
    o.runs = runs;
    o.hold_sightings = c.hold_sightings;
    o.hold_depth_precision = c.hold_depth_precision;
    results.push_back(swf::eval::RunNees(c.name, o));
  }
  const NeesResult& first = results.front();
  std::vector<Series> pose;
  std::vector<Series> landmark;
  Json config_json = Json::array();
  char buf[2048];
  for (std::size_t i = 0; i < results.size(); ++i) {
    const NeesResult& r = results[i];
    // Frame 1 is left out: its pose is the prior's centre (the truth), NEES ~0 by construction.
    pose.push_back({r.name, std::vector<double>(r.pose_nees.begin() + 1, r.pose_nees.end())});
    landmark.push_back(
        {r.name, std::vector<double>(r.landmark_nees.begin() + 1, r.landmark_nees.end())});
    Json config = {{"name", r.name}};
    SetNumber(&config, "mean_pose_nees", r.mean_pose_nees);
    SetNumber(&config, "mean_landmark_nees", r.mean_landmark_nees);
    SetNumber(&config, "pose_fraction_inside", r.pose_fraction_inside);
    SetNumber(&config, "landmark_fraction_inside", r.landmark_fraction_inside);
    config["pose_consistent"] =
        r.mean_pose_nees >= r.pose_lower && r.mean_pose_nees <= r.pose_upper;
    config["landmark_consistent"] =
        r.mean_landmark_nees >= r.landmark_lower && r.mean_landmark_nees <= r.landmark_upper;
    config["covariance_failures"] = r.covariance_failures;
    config["update_failures"] = r.update_failures;
    config["final_error_m"] = Numbers({r.final_error_m[0], r.final_error_m[1], r.final_error_m[2]});
    config["final_sigma_m"] = Numbers({r.final_sigma_m[0], r.final_sigma_m[1], r.final_sigma_m[2]});
    SetNumber(&config, "mean_poses", r.mean_poses);
    config["max_poses"] = r.max_poses;
    config_json.push_back(config);
  }
  Json summary = {{"runs", runs}, {"configs", config_json}, {"pose_dof", 6}};
  SetNumber(&summary, "pose_lower_95", first.pose_lower);
  SetNumber(&summary, "pose_upper_95", first.pose_upper);
  summary["landmark_dof"] = 3;
  SetNumber(&summary, "landmark_lower_95", first.landmark_lower);
  SetNumber(&summary, "landmark_upper_95", first.landmark_upper);
  const std::size_t frames = first.pose_nees.size() - 1;
  std::vector<double> frame_numbers;
  for (std::size_t k = 0; k < frames; ++k) frame_numbers.push_back(static_cast<double>(k + 2));
  pose.push_back({"95% lower", std::vector<double>(frames, first.pose_lower)});
  pose.push_back({"95% upper", std::vector<double>(frames, first.pose_upper)});
  landmark.push_back({"95% lower", std::vector<double>(frames, first.landmark_lower)});
  landmark.push_back({"95% upper", std::vector<double>(frames, first.landmark_upper)});
  const std::string of_runs = ", mean of " + RunsText(runs) + ", with its 95% bounds";
  const Figure pose_figure{"Consistency: NEES of the newest pose (6 dof)" + of_runs, "frame number",
                           "pose NEES (6 when consistent)", true};
  const Figure landmark_figure{"Consistency: NEES of the active landmarks (3 dof)" + of_runs,
                               "frame number", "landmark NEES (3 when consistent)", true};
  if (!WriteExperiment(out, "nees_pose", pose_figure, pose, summary, frame_numbers)) return false;
  if (!WriteExperiment(out, "nees_landmark", landmark_figure, landmark, summary, frame_numbers)) {
    return false;
  }
  AddParagraph(md, "## Consistency: NEES over " + std::to_string(runs) + " Monte Carlo runs");
  AddParagraph(md, "![nees pose](eval/nees_pose.png) ![nees landmark](eval/nees_landmark.png)");
  AddParagraph(
      md,
      "Normalized estimation error squared of the newest pose (6 dof, error in the estimator's "
      "own retraction, against `ComputeCovariances`' marginal) and of the active landmarks (3 "
      "dof, averaged over the landmarks of a run), averaged over the runs at every frame. The "
      "bounds are the two-sided 95% chi-square bounds of that run average, chi2(dof*runs)/runs "
      "(for landmarks conservative: landmarks of one run share the pose errors). Each run draws "
      "a new scene, new pixel noise (0.5 px, as R states) and new motion-input noise (as Q "
      "states); the first pose's prior is centred on the truth. Averages below are over frames "
      "2-40 (`out/eval/nees_pose.json`).");
  for (const NeesResult& r : results) {
    AddLine(md, "- " + r.name + ": " +
                    NeesVerdict("pose", r.mean_pose_nees, 6, r.pose_lower, r.pose_upper,
                                r.pose_fraction_inside) +
                    ". " +
                    NeesVerdict("Landmark", r.mean_landmark_nees, 3, r.landmark_lower,
                                r.landmark_upper, r.landmark_fraction_inside) +
                    ".");
  }
  AddLine(md, "");
  auto find = [&results](const char* name) -> const NeesResult& {
    for (const NeesResult& r : results)
      if (r.name == name) return r;
    return results.front();
  };
  const NeesResult& s5 = find("SWF(5) sideways");
  const NeesResult& s2 = find("SWF(2) sideways");
  const NeesResult& d5 = find("SWF(5) descent");
  const NeesResult& d10 = find("SWF(10) descent");
  const NeesResult& db = find("batch descent");
  const NeesResult& d30 = find("SWF(5) descent from 30 m");
  std::string over;
  for (const NeesResult& r : results) {
    if (r.mean_pose_nees <= r.pose_upper && r.mean_landmark_nees <= r.landmark_upper) continue;
    std::snprintf(buf, sizeof(buf), "%s%s (pose %.2fx, landmarks %.2fx in variance)",
                  over.empty() ? "" : "; ", r.name.c_str(), r.mean_pose_nees / 6,
                  r.mean_landmark_nees / 3);
    over += buf;
  }
  std::snprintf(buf, sizeof(buf),
                "Summary, measured: on the sideways scene SWF(2)/SWF(5)/SWF(10) pose NEES "
                "%.2f/%.2f/%.2f (expected 6), landmarks %.2f/%.2f/%.2f (expected 3). "
                "Overconfident beyond the 95%% bound: %s. ",
                s2.mean_pose_nees, s5.mean_pose_nees, find("SWF(10) sideways").mean_pose_nees,
                s2.mean_landmark_nees, s5.mean_landmark_nees,
                find("SWF(10) sideways").mean_landmark_nees, over.empty() ? "none" : over.c_str());
  std::string summary_text = buf;
  if (d5.mean_pose_nees > d5.pose_upper) {
    std::snprintf(
        buf, sizeof(buf),
        "On the descent from 100 m the pose NEES falls with the window (SWF(5) %.2fx, SWF(10) "
        "%.2fx, batch %.2fx) and the same descent started at 30 m gives %.2fx: the excess comes "
        "from linearizing at long range (23 px disparity at 100 m against 0.5 px noise) and is "
        "frozen into the prior the shorter the window is.",
        d5.mean_pose_nees / 6, d10.mean_pose_nees / 6, db.mean_pose_nees / 6,
        d30.mean_pose_nees / 6);
    summary_text += buf;
  }
  const NeesResult& h5 = find("SWF(5) descent, held");
  const NeesResult& h10 = find("SWF(10) descent, held");
  std::snprintf(
      buf, sizeof(buf),
      " Holding the oldest pose while it sees a tracked landmark with fewer than %d sightings "
      "(`SwfOptions::hold_sightings`, docs/integrity.md): SWF(5) %.2fx, SWF(10) %.2fx; x error at "
      "the last frame %.3f / %.3f m against %.3f / %.3f m without and %.3f m for batch; the "
      "window then holds %.1f / %.1f poses on average, at most %d / %d.",
      kHoldSightings, h5.mean_pose_nees / 6, h10.mean_pose_nees / 6, h5.final_error_m[0],
      h10.final_error_m[0], d5.final_error_m[0], d10.final_error_m[0], db.final_error_m[0],
      h5.mean_poses, h10.mean_poses, h5.max_poses, h10.max_poses);
  summary_text += buf;
  const NeesResult& p5 = find("SWF(5) descent, held by depth");
  const NeesResult& p10 = find("SWF(10) descent, held by depth");
  const NeesResult& c30 = find("SWF(5) descent from 30 m, held");
  const NeesResult& p30 = find("SWF(5) descent from 30 m, held by depth");
  std::snprintf(
      buf, sizeof(buf),
      " Held instead while such a landmark's sightings know its depth to worse than %.1f%% "
      "(`SwfOptions::hold_depth_precision`): SWF(5) %.2fx, SWF(10) %.2fx, x error %.3f / %.3f m, "
      "window %.1f / %.1f poses on average, at most %d / %d; on the descent from 30 m it holds "
      "%.1f poses on average, at most %d (the count: %.1f, at most %d), NEES %.2fx.",
      100 * kHoldDepth, p5.mean_pose_nees / 6, p10.mean_pose_nees / 6, p5.final_error_m[0],
      p10.final_error_m[0], p5.mean_poses, p10.mean_poses, p5.max_poses, p10.max_poses,
      p30.mean_poses, p30.max_poses, c30.mean_poses, c30.max_poses, p30.mean_pose_nees / 6);
  summary_text += buf;
  AddParagraph(md, summary_text);
  return true;
}

// Fig. 2b: depth error against the distance off the optical axis after 25 frames of a descent
// at 10 m/s and 10 Hz from 100 m to 75 m (the focus of expansion is the nadir): the estimators'
// RMS error of the landmarks' heights and the Cramer-Rao bound, after one frame and after all.
bool AddFig02b(const Output& out, int monte_carlo_runs, std::string* md) {
  // Four scenes per Monte Carlo run: a 2 m bin at the axis holds about 2 of a scene's landmarks.
  const int runs = 4 * monte_carlo_runs;
  SceneOptions so;
  so.frames = 25;
  so.start_altitude_m = 100.0;
  so.step_m = 1.0;
  so.num_landmarks = 150;
  so.landmark_radius_m = 16.0;  // the last frame's half-width at 75 m is 16.6 m
  constexpr double kBinM = 2.0;
  constexpr int kBins = 8;
  struct Bins {
    std::vector<double> sum = std::vector<double>(kBins, 0.0);
    std::vector<int> count = std::vector<int>(kBins, 0);
    void Add(double off_axis_m, double squared) {
      const int b = static_cast<int>(off_axis_m / kBinM);
      if (b < 0 || b >= kBins) return;
      sum[b] += squared;
      ++count[b];
    }
    std::vector<double> Root() const {
      std::vector<double> r;
      for (int b = 0; b < kBins; ++b)
        r.push_back(count[b] > 0 ? std::sqrt(sum[b] / count[b]) : std::nan(""));
      return r;
    }
  };
  // Distance of a landmark from the nadir of a pose (the optical axis at the ground).
  const auto off_axis = [](const Pose<double>& pose, const Vec3<double>& p) {
    return std::hypot(p.x() - pose.t.x(), p.y() - pose.t.y());
  };
  const auto estimator_bins = [&](SwfMode mode, int window) {
    Bins bins;
    for (int r = 0; r < runs; ++r) {
      SceneOptions sr = so;
      sr.seed = 200 + static_cast<std::uint64_t>(r);
      const SyntheticScene scene(sr);
      const auto last = [&](Filter* swf, std::size_t j) {
        if (j + 1 != scene.frames().size()) return;
        const Pose<double>& truth = scene.frames()[j].truth;
        swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int) {
          const Vec3<double>& t = scene.landmarks()[id];
          bins.Add(off_axis(truth, t), (p.z() - t.z()) * (p.z() - t.z()));
        });
      };
      (void)RunFilter<Filter>(scene, mode, window, 2000 + static_cast<std::uint64_t>(r), last);
    }
    return bins;
  };
  const Bins swf5 = estimator_bins(SwfMode::kSlidingWindow, 5);
  const Bins batch = estimator_bins(SwfMode::kBatch, 40);
  // The bound on the same scenes, so both sides average over the same landmarks.
  Bins crlb_first;
  Bins crlb_last;
  for (int r = 0; r < runs; ++r) {
    SceneOptions sc = so;
    sc.seed = 200 + static_cast<std::uint64_t>(r);
    const SyntheticScene scene(sc);
    const auto& last_frame = scene.frames().back();
    AtTruth(sc, [&](const Filter& swf, std::size_t j) {
      if (j != 0 && j + 1 != scene.frames().size()) return;
      swf.ForEachLandmark([&](std::int64_t id, const Vec3<double>&, int) {
        Mat3<double> c;
        if (!swf.GetLandmarkCovariance(id, &c)) return;
        // Only the landmarks still in view at the end, binned by their final distance off axis.
        const bool in_view = std::any_of(last_frame.obs.begin(), last_frame.obs.end(),
                                         [id](const auto& o) { return o.id == id; });
        if (in_view) {
          (j == 0 ? crlb_first : crlb_last)
              .Add(off_axis(last_frame.truth, scene.landmarks()[id]), c(2, 2));
        }
      });
    });
  }
  std::vector<double> x;
  for (int b = 0; b < kBins; ++b) x.push_back((b + 0.5) * kBinM);
  std::vector<Series> series{{"SWF(5)", swf5.Root()},
                             {"batch", batch.Root()},
                             {"CRLB after 25 frames", crlb_last.Root()},
                             {"CRLB of the first frame alone", crlb_first.Root()}};
  const std::vector<double>& s = series[0].y;
  const std::vector<double>& bt = series[1].y;
  const std::vector<double>& cl = series[2].y;
  const std::vector<double>& c1 = series[3].y;
  // An empty bin has no RMS: null in the lists.
  const Json json = {{"runs", runs},
                     {"bin_m", kBinM},
                     {"landmarks_per_bin", swf5.count},
                     {"swf5_rms_m", Numbers(s)},
                     {"batch_rms_m", Numbers(bt)},
                     {"crlb_25_frames_m", Numbers(cl)},
                     {"crlb_first_frame_m", Numbers(c1)}};
  const Figure figure{
      "Fig. 2b: height error off the optical axis, 100 m to 75 m (" + RunsText(runs) + ")",
      "distance off the optical axis at the ground after 25 frames (m)",
      "landmark height error, RMS or 1 sigma (m)", true};
  if (!WriteExperiment(out, "fig02b_focus_of_expansion", figure, series, json, x)) return false;
  char buf[2048];
  *md +=
      "## Fig. 2b: depth at the focus of "
      "expansion\n\n![fig02b](eval/fig02b_focus_of_expansion.png)\n\n";
  std::snprintf(
      buf, sizeof(buf),
      "Descent at 10 m/s and 10 Hz from 100 m to 75 m, 25 frames, 150 landmarks within 16 m of "
      "the nadir, 0.5 px noise, the 1 m baseline EDL rig at 1024x768 (the paper: 512x384). Height "
      "error (the depth along the nadir axis) of the landmarks in view at the end, binned by "
      "their final distance from the nadir, over the runs' scenes (%d / %d / %d landmarks in "
      "the bins quoted; the bound on the same scenes). Nearest bin (0-2 m) / 8-10 m / 12-14 m: "
      "SWF(5) "
      "%.3f / %.3f / %.3f m RMS, batch %.3f / %.3f / %.3f m, CRLB after 25 frames %.3f / %.3f / "
      "%.3f m, CRLB of the first frame alone %.3f / %.3f / %.3f m. Paper: fusing over time gives "
      "a motion-baseline effect, more certain estimates farther off the viewing axis, and stereo "
      "observes depth at the focus of expansion where a monocular camera cannot. Ours: %s",
      swf5.count[0], swf5.count[4], swf5.count[6], s[0], s[4], s[6], bt[0], bt[4], bt[6], cl[0],
      cl[4], cl[6], c1[0], c1[4], c1[6],
      cl[6] < cl[0] ? "the bound after 25 frames falls off the axis, the motion-baseline effect; "
                      "at the axis it is finite, from the stereo baseline alone."
                    : "the bound after 25 frames does not fall off the axis on this scene.");
  *md += std::string(buf) + "\n\n";
  return true;
}

// Fig. 16: final map MSE against average track length and window size.
bool AddFig16(const Output& out, int runs, std::string* md) {
  swf::eval::TrackLengthOptions o;
  o.runs = runs;
  const auto points = swf::eval::RunTrackLengthStudy(o);
  std::vector<double> x;
  std::vector<Series> series;
  for (std::size_t w = 0; w < o.windows.size(); ++w) {
    series.push_back({"SWF(" + std::to_string(o.windows[w]) + ")", {}});
  }
  Json rows = Json::array();
  char buf[2048];
  double features = 0.0;
  for (const auto& p : points) {
    x.push_back(p.mean_track_length);
    features += p.mean_features_per_frame / static_cast<double>(points.size());
    for (std::size_t w = 0; w < o.windows.size(); ++w) series[w].y.push_back(p.final_mse_m2[w]);
    Json row = Json::object();
    SetNumber(&row, "step_m", p.step_m);
    SetNumber(&row, "mean_track_length", p.mean_track_length);
    SetNumber(&row, "features_per_frame", p.mean_features_per_frame);
    row["final_mse_m2"] = Numbers(p.final_mse_m2);
    rows.push_back(row);
  }
  // How much each axis moves the MSE: the largest max/min ratio along a row (window, fixed track
  // length) and along a column (track length, fixed window).
  double across_windows = 1.0;
  for (const auto& p : points) {
    const auto [lo, hi] = std::minmax_element(p.final_mse_m2.begin(), p.final_mse_m2.end());
    across_windows = std::max(across_windows, *hi / *lo);
  }
  double across_tracks = 1.0;
  for (const Series& s : series) {
    const auto [lo, hi] = std::minmax_element(s.y.begin(), s.y.end());
    across_tracks = std::max(across_tracks, *hi / *lo);
  }
  Json summary = {{"runs", runs}, {"frames", o.frames}, {"windows", o.windows}};
  SetNumber(&summary, "max_ratio_across_windows", across_windows);
  SetNumber(&summary, "max_ratio_across_track_lengths", across_tracks);
  summary["points"] = rows;
  const Figure figure{"Fig. 16: final landmark error against track length, per window size (" +
                          RunsText(runs) + ")",
                      "average track length (frames)", "final landmark mean squared error (m^2)",
                      true};
  if (!WriteExperiment(out, "fig16_track_length", figure, series, summary, x)) {
    return false;
  }
  AddParagraph(md, "## Fig. 16: final map MSE against average track length and window size");
  AddParagraph(md, "![fig16](eval/fig16_track_length.png)");
  std::string table = "| track length |";
  for (int k : o.windows) table += " SWF(" + std::to_string(k) + ") |";
  AddLine(md, table);
  table = "|---|";
  for (std::size_t w = 0; w < o.windows.size(); ++w) table += "---|";
  AddLine(md, table);
  for (const auto& p : points) {
    std::snprintf(buf, sizeof(buf), "| %.1f |", p.mean_track_length);
    table = buf;
    for (double v : p.final_mse_m2) {
      std::snprintf(buf, sizeof(buf), " %.3g |", v);
      table += buf;
    }
    AddLine(md, table);
  }
  AddLine(md, "");
  // Where the window matters: the window ratio at long tracks (>= 8 frames) and the largest
  // ratio of the shortest window over the longest.
  double long_ratio = 1.0;
  double short_ratio = 1.0;
  double short_length = 0.0;
  for (const auto& p : points) {
    const auto [lo, hi] = std::minmax_element(p.final_mse_m2.begin(), p.final_mse_m2.end());
    if (p.mean_track_length >= 8.0) long_ratio = std::max(long_ratio, *hi / *lo);
    const double r = p.final_mse_m2.front() / p.final_mse_m2.back();
    if (r > short_ratio) {
      short_ratio = r;
      short_length = p.mean_track_length;
    }
  }
  std::snprintf(
      buf, sizeof(buf),
      "Sideways flight at 50 m, %d frames, %.0f features per frame on average (paper: ~30), the "
      "frame step setting the track length; final MSE (m^2) of every landmark seen, %d runs per "
      "point. Changing the track length moves the MSE by up to %.0fx at a fixed window; with "
      "tracks of 8 frames or more the window moves it by at most %.2fx. Paper: MSE largely "
      "independent of window size, track length matters more. ",
      o.frames, features, runs, across_tracks, long_ratio);
  std::string text = buf;
  if (short_ratio > 2.0) {
    std::snprintf(buf, sizeof(buf),
                  "Different from the paper: with short tracks the window matters here, SWF(%d) "
                  "ends %.1fx worse than SWF(%d) at %.1f-frame tracks (early marginalization of "
                  "poses whose landmarks have little parallax yet; see the NEES section for "
                  "whether the short window is also overconfident).",
                  o.windows.front(), short_ratio, o.windows.back(), short_length);
  } else {
    std::snprintf(buf, sizeof(buf),
                  "As in the paper: the shortest window is never worse than %.2fx the longest.",
                  std::max(short_ratio, 1.0));
  }
  text += buf;
  AddParagraph(md, text);
  return true;
}

// Fig. 12: static cameras, 30 landmarks.
bool AddFig12(const Output& output, int runs, std::string* md) {
  char buf[2048];
  SceneOptions so = swf::scene::StaticRig();
  so.frames = 40;
  Series swf5 = MonteCarlo("SWF(5)", so, runs, SwfRun(SwfMode::kSlidingWindow, 5));
  Series one_over_m{"1/m", {}};
  for (std::size_t k = 0; k < swf5.y.size(); ++k) one_over_m.y.push_back(swf5.y[0] / (k + 1));
  so.seed = 100;
  Series crlb{"CRLB", CramerRao(so)};
  Json summary = {{"runs", runs}};
  SetNumbers(&summary, {{"mse_m2_at_40", swf5.y.back()}, {"crlb_m2_at_40", crlb.y.back()}});
  const Figure figure{
      "Fig. 12: landmark error with static cameras, 30 landmarks (" + RunsText(runs) + ")",
      "frame number", kLandmarkMse, true};
  if (!WriteExperiment(output, "fig12_static", figure, {swf5, one_over_m, crlb}, summary)) {
    return false;
  }
  AddFigure(md, "## Fig. 12: static cameras, 30 landmarks", "![fig12](eval/fig12_static.png)");
  const double vs_one_over_m = swf5.y.back() / one_over_m.y.back();
  std::snprintf(
      buf, sizeof(buf),
      "SWF(5) MSE after 40 frames %.3g m^2; the 1/m curve from frame 1 gives %.3g m^2; CRLB "
      "%.3g m^2. Paper: convergence close to 1/m with stationary cameras. Ours: %.2fx the 1/m "
      "value and %.2fx the CRLB after 40 frames (%s).",
      swf5.y.back(), one_over_m.y.back(), crlb.y.back(), vs_one_over_m,
      swf5.y.back() / crlb.y.back(),
      vs_one_over_m < 1.5 && vs_one_over_m > 0.67
          ? "matches the paper"
          : "differs from the paper: the 1/m line is anchored at one noisy first frame, the "
            "CRLB is the measured reference");
  AddParagraph(md, buf);
  return true;
}

// Fig. 13: descent with 150 landmarks tracked throughout.
bool AddFig13(const Output& output, int runs, std::string* md) {
  char buf[2048];
  SceneOptions so;
  so.frames = 40;
  std::vector<Series> s;
  std::vector<double> rms_batch, rms_vo, rms_vo2, rms_s3, rms_s10, rms_plain3;
  s.push_back(MonteCarlo("batch", so, runs, SwfRun(SwfMode::kBatch, 40), &rms_batch));
  s.push_back(MonteCarlo("SWF(3)", so, runs, SwfRun(SwfMode::kSlidingWindow, 3), &rms_s3));
  s.push_back(MonteCarlo("SWF(4)", so, runs, SwfRun(SwfMode::kSlidingWindow, 4)));
  s.push_back(MonteCarlo("SWF(5)", so, runs, SwfRun(SwfMode::kSlidingWindow, 5)));
  s.push_back(MonteCarlo("SWF(10)", so, runs, SwfRun(SwfMode::kSlidingWindow, 10), &rms_s10));
  s.push_back(MonteCarlo("VO(10)", so, runs, SwfRun(SwfMode::kVisualOdometry, 10), &rms_vo));
  s.push_back(MonteCarlo("VO(2)", so, runs, SwfRun(SwfMode::kVisualOdometry, 2), &rms_vo2));
  // The paper's SWF relinearizes everything: "SWF(3-5) come close to batch" holds only with
  // first-estimate Jacobians (estimator/README.md, known limits).
  s.push_back(MonteCarlo(
      "SWF(3) relinearized (paper)", so, runs,
      [](const SyntheticScene& scene, std::uint64_t seed) {
        return RunFilter<Filter>(scene, SwfMode::kSlidingWindow, 3, seed, {}, kMotionSigmaM,
                                 kMotionSigmaRad, false);
      },
      &rms_plain3));
  so.seed = 100;
  s.push_back(Series{"CRLB", CramerRao(so)});
  // The paper's claim: over 10 frames SWF error ~76% below VO, std ~3.5x smaller.
  Json final_rms = Json::object();
  SetNumbers(&final_rms, {{"batch", Mean(rms_batch)},
                          {"swf3", Mean(rms_s3)},
                          {"swf10", Mean(rms_s10)},
                          {"vo10", Mean(rms_vo)},
                          {"swf3_relinearized", Mean(rms_plain3)}});
  Json summary = {{"runs", runs}, {"final_rms_m", final_rms}};
  SetNumbers(
      &summary,
      {{"swf10_error_below_vo10_percent", 100.0 * (1.0 - Mean(rms_s10) / Mean(rms_vo))},
       {"vo10_std_over_swf10_std", SampleStd(rms_vo) / std::max(SampleStd(rms_s10), 1e-12)},
       {"vo2_final_rms_m", Mean(rms_vo2)},
       {"swf10_error_below_vo2_percent", 100.0 * (1.0 - Mean(rms_s10) / Mean(rms_vo2))},
       {"vo2_std_over_swf10_std", SampleStd(rms_vo2) / std::max(SampleStd(rms_s10), 1e-12)}});
  const Figure figure{
      "Fig. 13: landmark error against window size on the descent, 150 "
      "landmarks, 100 m to 41.5 m (" +
          RunsText(runs) + ")",
      "frame number", kLandmarkMse, true};
  if (!WriteExperiment(output, "fig13_descent", figure, s, summary)) return false;
  AddFigure(md, "## Fig. 13: descent, 150 landmarks tracked throughout (100 m to 41.5 m)",
            "![fig13](eval/fig13_descent.png)");
  std::snprintf(
      buf, sizeof(buf),
      "Final landmark RMS: batch %.3f m, SWF(3) %.3f m, SWF(10) %.3f m, VO(10) %.3f m. "
      "Paper: 3-, 4-, 5-frame SWFs come close to batch. Ours: SWF(3) ends %+.0f%% and SWF(10) "
      "%+.0f%% from batch in RMS, **with first-estimate Jacobians (our default, not in the "
      "paper)**; the paper's SWF, which relinearizes every measurement of a prior landmark, "
      "ends SWF(3) at %.3f m, %.2fx batch in RMS (\"SWF(3) relinearized (paper)\" in the "
      "plot): the paper's claim holds here only with first-estimate Jacobians. What short "
      "windows lose is linearization error frozen into the prior at far altitude: the NEES "
      "section measures SWF(5) on this descent overconfident while batch and the same descent "
      "from 30 m are not (and with 0.01 px noise every window equals batch to 1e-5 m; "
      "estimator/README.md).",
      Mean(rms_batch), Mean(rms_s3), Mean(rms_s10), Mean(rms_vo),
      100.0 * (Mean(rms_s3) / Mean(rms_batch) - 1.0),
      100.0 * (Mean(rms_s10) / Mean(rms_batch) - 1.0), Mean(rms_plain3),
      Mean(rms_plain3) / Mean(rms_batch));
  AddParagraph(md, buf);
  std::snprintf(
      buf, sizeof(buf),
      "**Paper claim (4.2.4): over 10 frames SWF error ~76%% below VO, standard deviation "
      "~3.5x smaller.** Ours on this descent (final landmark RMS, %d runs): SWF(10) is %.0f%% "
      "below VO(10) (a 10-pose window that deletes instead of marginalizing), standard "
      "deviation ratio %.2f; against VO(2) (frame-to-frame, the paper's k=1 deleting "
      "filter) %.0f%% below, standard deviation ratio %.2f. %s",
      runs, 100.0 * (1.0 - Mean(rms_s10) / Mean(rms_vo)),
      SampleStd(rms_vo) / std::max(SampleStd(rms_s10), 1e-12),
      100.0 * (1.0 - Mean(rms_s10) / Mean(rms_vo2)),
      SampleStd(rms_vo2) / std::max(SampleStd(rms_s10), 1e-12),
      runs < 10 ? "The standard deviations come from fewer than 10 runs and are only "
                  "indicative. The paper does not state its VO's window or scene, so the "
                  "remaining gap to 76% is not attributable further."
                : "The paper does not state its VO's window or scene, so the remaining gap to "
                  "76% is not attributable further.");
  AddParagraph(md, buf);
  return true;
}

// Fig. 14: run time per frame and state-vector size.
bool AddFig14(const Output& output, std::string* md) {
  char buf[2048];
  SceneOptions so = swf::scene::Fig14Sideways();
  so.frames = 150;
  so.seed = 7;
  const SyntheticScene scene(so);
  const Trace batch = RunFilter<BigBatch>(scene, SwfMode::kBatch, 150, 1);
  double features_per_frame = 0.0;
  for (const auto& f : scene.frames()) {
    features_per_frame += static_cast<double>(f.obs.size()) / scene.frames().size();
  }
  const Trace s10 = RunFilter<Filter>(scene, SwfMode::kSlidingWindow, 10, 1);
  const Trace s20 = RunFilter<Filter>(scene, SwfMode::kSlidingWindow, 20, 1);
  const Figure runtime{"Fig. 14a: time of one filter update, sideways motion (one run)",
                       "frame number", "Update() wall-clock time (ms)", true};
  if (!WriteExperiment(
          output, "fig14a_runtime", runtime,
          {{"batch", batch.update_ms}, {"SWF(10)", s10.update_ms}, {"SWF(20)", s20.update_ms}},
          {{"note", "wall-clock ms of Update() on the 2-core VM"}})) {
    return false;
  }
  so.step_m = 4.4;  // ~5-frame tracks
  so.landmark_density_per_m2 = 0.08;
  so.frames = 100;
  const SyntheticScene scene_b(so);
  const Trace with = RunFilter<Filter>(scene_b, SwfMode::kSlidingWindow, 2, 1);
  const Trace without = RunFilter<BigBatch>(scene_b, SwfMode::kBatch, 100, 1);
  Json state_summary = Json::object();
  SetNumbers(&state_summary, {{"mean_state_dim_swf2", Mean(with.state_dim)},
                              {"final_state_dim_batch", without.state_dim.back()}});
  const Figure state{"Fig. 14b: state-vector size with and without marginalization", "frame number",
                     "state dimension (scalars)", false};
  if (!WriteExperiment(output, "fig14b_state_size", state,
                       {{"SWF(2) with marginalization", with.state_dim},
                        {"without marginalization", without.state_dim}},
                       state_summary)) {
    return false;
  }
  AddFigure(md, "## Fig. 14: run time and state size",
            "![fig14a](eval/fig14a_runtime.png) ![fig14b](eval/fig14b_state_size.png)");
  std::snprintf(
      buf, sizeof(buf),
      "Per-frame update (wall clock, shared VM, one run): median over the 150 frames SWF(10) "
      "%.2f ms, SWF(20) %.2f ms; batch %.1f ms at frame 150 and growing. Mean state size "
      "SWF(10) %.0f, SWF(20) %.0f (paper: ~132 and ~172 with 76 landmarks and ~20 features "
      "per frame; ours sees %.0f features per frame). State size with a 2-frame window: mean "
      "%.0f, without marginalization %.0f after 100 frames (paper: bounded vs growing). "
      "Benchmarks with medians: docs/benchmarks.md.",
      Median(s10.update_ms), Median(s20.update_ms), batch.update_ms.back(), Mean(s10.state_dim),
      Mean(s20.state_dim), features_per_frame, Mean(with.state_dim), without.state_dim.back());
  AddParagraph(md, buf);
  return true;
}

// Fig. 15: sideways motion, ~85% overlap, ~25 features per frame.
bool AddFig15(const Output& output, int runs, std::string* md) {
  char buf[2048];
  const SceneOptions so = swf::scene::Fig15Sideways();
  std::vector<Series> s;
  s.push_back(MonteCarlo("batch", so, runs, SwfRun(SwfMode::kBatch, 40)));
  s.push_back(MonteCarlo("SWF(2)", so, runs, SwfRun(SwfMode::kSlidingWindow, 2)));
  s.push_back(MonteCarlo("SWF(10)", so, runs, SwfRun(SwfMode::kSlidingWindow, 10)));
  // The paper's SWF relinearizes everything (no first-estimate Jacobians): with world points
  // and with the inverse depth the paper suggests for early marginalization.
  auto plain = [](SwfMode mode, int k, bool inverse_depth) {
    return [=](const SyntheticScene& scene, std::uint64_t seed) {
      return inverse_depth ? RunFilter<InverseDepthFilter>(scene, mode, k, seed, {}, kMotionSigmaM,
                                                           kMotionSigmaRad, false)
                           : RunFilter<Filter>(scene, mode, k, seed, {}, kMotionSigmaM,
                                               kMotionSigmaRad, false);
    };
  };
  s.push_back(
      MonteCarlo("SWF(2) relinearized", so, runs, plain(SwfMode::kSlidingWindow, 2, false)));
  s.push_back(MonteCarlo("SWF(2) relinearized, inverse depth", so, runs,
                         plain(SwfMode::kSlidingWindow, 2, true)));
  const Figure figure{
      "Fig. 15: landmark error with sideways motion, ~85% overlap (" + RunsText(runs) + ")",
      "frame number", kLandmarkMse, true};
  if (!WriteExperiment(output, "fig15_sideways", figure, s, {{"runs", runs}})) return false;
  AddFigure(md, "## Fig. 15: sideways motion, ~85% overlap", "![fig15](eval/fig15_sideways.png)");
  std::snprintf(
      buf, sizeof(buf),
      "Final MSE: batch %.3g, SWF(2) %.3g, SWF(10) %.3g m^2 (first-estimate Jacobians, our "
      "default). Paper: the 2-frame SWF suffers from early marginalization, the 10-frame SWF "
      "follows batch. With the paper's plain relinearization SWF(2) ends at %.2fx the batch "
      "MSE with world-point landmarks and %.2fx with inverse depth (the paper's suggested "
      "remedy): the paper's effect is %s, and inverse depth reduces it. First-estimate "
      "Jacobians remove it: SWF(2) %.2fx, SWF(10) %.2fx batch.",
      s[0].y.back(), s[1].y.back(), s[2].y.back(), s[3].y.back() / s[0].y.back(),
      s[4].y.back() / s[0].y.back(),
      s[3].y.back() > 1.5 * s[0].y.back() ? "reproduced" : "not reproduced on this scene",
      s[1].y.back() / s[0].y.back(), s[2].y.back() / s[0].y.back());
  AddParagraph(md, buf);
  return true;
}

// Fig. 17: VSDF against SWF with three active frames, every landmark in every frame. The VSDF
// twice: eq. 12 as we fly it (the Schur term's blocks within each variable) and read literally
// (only its scalar diagonal, SwfOptions::vsdf_scalar_diagonal).
bool AddFig17(const Output& output, int runs, std::string* md) {
  char buf[2048];
  SceneOptions so;
  so.frames = 40;
  so.num_landmarks = 100;
  const auto vsdf_diagonal = [](const SyntheticScene& scene, std::uint64_t seed) {
    return RunFilter<Filter>(scene, SwfMode::kVsdf, 3, seed, {}, kMotionSigmaM, kMotionSigmaRad,
                             true, true);
  };
  std::vector<Series> s;
  std::vector<double> mse_swf, mse_block, mse_diagonal;
  int failed_swf = 0, failed_block = 0, failed_diagonal = 0;
  s.push_back(MonteCarlo("SWF(3)", so, runs, SwfRun(SwfMode::kSlidingWindow, 3), nullptr, &mse_swf,
                         &failed_swf));
  s.push_back(MonteCarlo("VSDF(3), block diagonal", so, runs, SwfRun(SwfMode::kVsdf, 3), nullptr,
                         &mse_block, &failed_block));
  s.push_back(MonteCarlo("batch", so, runs, SwfRun(SwfMode::kBatch, 40)));
  Series diagonal_median;
  s.push_back(MonteCarlo("VSDF(3), diagonal elements", so, runs, vsdf_diagonal, nullptr,
                         &mse_diagonal, &failed_diagonal, &diagonal_median));
  s.push_back(diagonal_median);
  // Medians over the runs beside the means: one run that runs away dominates a mean.
  const double swf3 = Median(mse_swf);
  const double block = Median(mse_block);
  const double diagonal = Median(mse_diagonal);
  int diverged = 0;  // runs ending above 10x the median SWF(3) MSE
  for (double m : mse_diagonal) diverged += m > 10.0 * swf3 ? 1 : 0;
  Json mean_mse = Json::object();
  SetNumbers(&mean_mse, {{"swf3", s[0].y.back()},
                         {"vsdf3_block", s[1].y.back()},
                         {"batch", s[2].y.back()},
                         {"vsdf3_diagonal", s[3].y.back()}});
  Json median_mse = Json::object();
  SetNumbers(&median_mse, {{"swf3", swf3}, {"vsdf3_block", block}, {"vsdf3_diagonal", diagonal}});
  const Json summary = {
      {"runs", runs},
      {"final_mse_m2_mean", mean_mse},
      {"final_mse_m2_median", median_mse},
      {"failed_updates",
       {{"swf3", failed_swf}, {"vsdf3_block", failed_block}, {"vsdf3_diagonal", failed_diagonal}}},
      {"vsdf3_diagonal_diverged_runs", diverged}};
  const Figure figure{
      "Fig. 17: landmark error of VSDF and SWF, 3 active frames, 100 "
      "landmarks (" +
          RunsText(runs) + ")",
      "frame number", kLandmarkMse, true};
  if (!WriteExperiment(output, "fig17_vsdf", figure, s, summary)) return false;
  AddFigure(md, "## Fig. 17: VSDF against SWF, 3 active frames", "![fig17](eval/fig17_vsdf.png)");
  const auto verdict = [swf3](double vsdf) {
    return vsdf > 1.2 * swf3 ? "worse than SWF(3), the paper's ordering"
                             : "within 20% of SWF(3): the paper's clear difference is not "
                               "reproduced";
  };
  std::snprintf(
      buf, sizeof(buf),
      "Final MSE, median over the %d runs (the plot shows means, and the diagonal variant's "
      "median too): SWF(3) %.3g m^2 (batch, "
      "mean, %.3g m^2); VSDF(3) with the Schur term's blocks within each variable (what "
      "`SwfMode::kVsdf` flies) %.3g m^2, %.2fx SWF(3), %s; VSDF(3) with only the diagonal "
      "elements of the Schur term (eq. 12 read literally, `SwfOptions::vsdf_scalar_diagonal`) "
      "%.3g m^2, %.2fx SWF(3), %s. The diagonal variant ran away in %d of %d runs (final MSE "
      "above 10x SWF(3)'s; its mean ends at %.3g m^2) with %d failed updates (SWF(3): %d, "
      "block-diagonal VSDF: %d). Paper: VSDF converges worse; \"a majority of the usefulness "
      "of carrying a prior comes from the off-diagonal terms\".",
      runs, swf3, s[2].y.back(), block, block / swf3, verdict(block), diagonal, diagonal / swf3,
      verdict(diagonal), diverged, runs, s[3].y.back(), failed_diagonal, failed_swf, failed_block);
  AddParagraph(md, buf);
  AddParagraph(
      md,
      "Why the two readings differ: subtracting only part of a positive semi-definite Schur "
      "term from the information matrix does not keep the result positive definite. Lambda_rr "
      "keeps its own off-diagonal elements (the marginalized pose's measurements couple each "
      "landmark's x, y and depth, and the next pose's six coordinates) while the diagonal "
      "loses what the exact complement would take from them, so the prior can claim more "
      "correlation than variance. Keeping whole blocks within each variable removes that "
      "inside a variable, and only the fill-in *between* variables is dropped: the "
      "correlation that the marginalized pose's uncertainty puts between its landmarks, which "
      "matters only when the pose is weakly determined relative to the landmarks; with 100 "
      "landmarks tracked it is not. Measured in the estimator (estimator/README.md, known "
      "limits): with 10-50 landmarks in the linear regime the block-diagonal VSDF is 7-15% "
      "worse in MSE on average (too little against run-to-run spread to assert), and in the "
      "nonlinear regime (20 landmarks from 100 m, loose motion input) it is better, because "
      "the dense prior also carries the linearization error of a weakly determined pose. "
      "Where the block-diagonal VSDF does fail clearly is the covariance: the NEES section "
      "below runs it on the same descents as SWF, and its marginals are several times "
      "over-confident where SWF's are consistent.");
  return true;
}

// Real data: kitti-vo batch against sliding windows on the same global cost.
bool AddKittiWindows(const Output& output, const std::string& shared, std::string* md) {
  char buf[2048];
  swf::tools::KittiVoProblem problem;
  std::string error;
  const std::string dir = shared + "/data/kitti-vo/";
  if (!swf::tools::LoadKittiVo(dir + "VO_calibration.txt", dir + "VO_camera_poses_large.txt",
                               dir + "VO_stereo_factors_large.txt", &problem, &error)) {
    std::fprintf(stderr, "swf-eval: %s\n", error.c_str());
    return false;
  }
  swf::tools::KittiVoSolver solver;  // one ~40 MB filter for every window
  const auto batch = solver.Solve(problem, 0);
  Series cost{"final cost", {}};
  Series dpos{"max position difference to batch (m)", {}};
  Json list = Json::array();
  std::vector<double> windows;
  for (int k : {2, 3, 5, 10, 20}) {
    windows.push_back(k);
    const auto r = solver.Solve(problem, k);
    double worst = 0;
    for (std::size_t j = 0; j < r.poses.size(); ++j)
      worst = std::max(worst, (r.poses[j].t - batch.poses[j].t).norm());
    cost.y.push_back(r.final_cost);
    dpos.y.push_back(worst);
    Json row = {{"window", k}};
    SetNumbers(&row, {{"final_cost", r.final_cost}, {"max_position_diff_m", worst}});
    list.push_back(row);
  }
  Json summary = Json::object();
  SetNumbers(&summary,
             {{"initial_cost", batch.initial_cost}, {"batch_final_cost", batch.final_cost}});
  summary["windows"] = list;
  const Figure figure{"kitti-vo: sliding windows against batch on the same global cost",
                      "window size (frames)",
                      "final cost (unitless), position difference to batch (m)", true};
  if (!WriteExperiment(output, "kitti_windows", figure, {cost, dpos}, summary, windows))
    return false;
  AddParagraph(md, "## Real data: kitti-vo, batch against sliding windows");
  std::snprintf(
      buf, sizeof(buf),
      "Initial cost %.6g, batch optimum %.6g (equal to Ceres's, tested). Windowed final costs "
      "on the same global cost, windows 2/3/5/10/20: %.6g / %.6g / %.6g / %.6g / %.6g; largest "
      "camera position difference to batch: %.3g / %.3g / %.3g / %.3g / %.3g m.",
      batch.initial_cost, batch.final_cost, cost.y[0], cost.y[1], cost.y[2], cost.y[3], cost.y[4],
      dpos.y[0], dpos.y[1], dpos.y[2], dpos.y[3], dpos.y[4]);
  AddParagraph(md, buf);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "swf-eval: reruns the paper's experiments (paper) and the flight pipeline on real image "
      "sequences (euroc, kitti); exit 3 when a run failed (non-finite, diverged, or a frame "
      "without tracked landmarks)"};
  swf::ground_cli::Adopt(&app, "swf-eval");
  app.require_subcommand(1);
  swf::eval::SequenceArgs sequence;
  std::vector<double> motion_sigma;
  // The options both sequence commands take.
  const auto add_sequence = [&](CLI::App* cmd) {
    cmd->add_option("DIR", sequence.dir, "the dataset folder")
        ->required()
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--out", sequence.out, "output directory (created)")->capture_default_str();
    cmd->add_option("--window", sequence.window, "poses in the window (the flight capacity)")
        ->capture_default_str()
        ->check(CLI::Range(2, 10));
    cmd->add_option("--max-tracks", sequence.max_tracks,
                    "tracked features (default " +
                        std::to_string(swf::eval::RunOptions{}.max_tracks) + " for euroc, " +
                        std::to_string(swf::eval::KittiRunOptions().max_tracks) + " for kitti)")
        ->check(CLI::Range(10, static_cast<int>(swf::frontend::kMaxTracks)));
    cmd->add_option("--motion-sigma", motion_sigma, "motion input sigma M,RAD")
        ->delimiter(',')
        ->expected(2)
        ->check(CLI::PositiveNumber);
    cmd->add_option("--divergence-m", sequence.divergence_m,
                    "error without fit that calls a run diverged")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--measurements", sequence.measurements,
                    "write the SWF run's front-end measurements, landmarks and true poses to "
                    "this JSON file (tools/eval/real_frames.py)");
  };
  double loop_seconds = 0.0;
  CLI::App* euroc = app.add_subcommand("euroc", "a EuRoC ASL sequence through the pipeline");
  add_sequence(euroc);
  euroc
      ->add_option("--loop-seconds", loop_seconds,
                   "play the frames forwards and backwards for this long")
      ->check(CLI::Range(0.0, 3600.0));
  int max_disparity_px = 128;
  int max_frames = 0;
  CLI::App* kitti = app.add_subcommand("kitti", "a KITTI odometry excerpt through the pipeline");
  add_sequence(kitti);
  kitti->add_option("--max-disparity", max_disparity_px, "the front end's disparity search")
      ->capture_default_str()
      ->check(CLI::Range(16, swf::frontend::kMaxDisparity));
  kitti->add_option("--frames", max_frames, "only the first N frames")
      ->check(CLI::Range(3, 1000000));
  std::string out;
  int runs = 5;
  int nees_runs = 50;
  std::string shared = swf::ground_cli::SharedDir();
  std::string only_list;
  CLI::App* paper =
      app.add_subcommand("paper", "the paper's experiments -> OUT/*.json, results.md");
  paper->add_option("OUT", out, "output directory (created)")->required();
  paper->add_option("--runs", runs, "Monte Carlo runs")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  paper->add_option("--nees-runs", nees_runs, "runs of the NEES section")
      ->capture_default_str()
      ->check(CLI::Range(2, 100000));
  paper->add_option("--shared", shared, "the shared data directory")->capture_default_str();
  paper->add_option(
      "--only", only_list,
      "comma-separated subset of fig02b,fig12,fig13,fig14,fig15,fig16,fig17,nees,kitti");
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  // Echoed as "run" into every JSON file the command writes (docs/cli.md).
  const swf::eval::Json run(swf::ground_cli::RunEcho(app, "swf-eval", argc, argv));
  sequence.run = run;
  if (motion_sigma.size() == 2) {
    sequence.motion_sigma_m = motion_sigma[0];
    sequence.motion_sigma_rad = motion_sigma[1];
  }
  if (euroc->parsed()) return swf::eval::RunEurocCommand(sequence, loop_seconds);
  if (kitti->parsed()) return swf::eval::RunKittiCommand(sequence, max_disparity_px, max_frames);
  const std::string only = only_list.empty() ? "" : "," + only_list + ",";
  std::string dir_error;
  if (!swf::cli::MakeDirectories(out, &dir_error)) {
    std::fprintf(stderr, "swf-eval paper: %s\n", dir_error.c_str());
    return 1;
  }
  const Output output{out, run};
  auto want = [&only](const char* name) {
    return only.empty() || only.find("," + std::string(name) + ",") != std::string::npos;
  };
  std::string md;  // docs/results.md, written from the same numbers as the JSON files
  AddLine(&md, "# Results: the paper's experiments rerun");
  AddLine(&md, "");
  AddLine(&md,
          "Generated by `tools/run eval` (`swf-eval paper out/eval --runs " + std::to_string(runs) +
              "` and `swf-eval euroc`); every number below is in a JSON file under `out/eval/` "
              "from the same run. Scenes are measurement-level (the estimator's synthetic scene: "
              "EDL rig, 1 m baseline, ~25 deg FOV, 1024x768, 0.5 px noise, IMU-like motion input "
              "10 cm / 2 mrad per frame). Errors are mean squared landmark error against truth "
              "over every landmark seen so far, averaged over the Monte Carlo runs.");
  AddLine(&md, "");
  // The sections in the order of the paper; the experiments are described at their functions.
  if (want("fig02b") && !AddFig02b(output, runs, &md)) return 1;
  if (want("fig12") && !AddFig12(output, runs, &md)) return 1;
  if (want("fig13") && !AddFig13(output, runs, &md)) return 1;
  if (want("fig14") && !AddFig14(output, &md)) return 1;
  if (want("fig15") && !AddFig15(output, runs, &md)) return 1;
  if (want("fig16") && !AddFig16(output, runs, &md)) return 1;
  if (want("fig17") && !AddFig17(output, runs, &md)) return 1;
  if (want("nees") && !AddNees(output, nees_runs, &md)) return 1;
  if (want("kitti") && !AddKittiWindows(output, shared, &md)) return 1;
  std::ofstream md_file(out + "/results.md");
  md_file << md;
  if (!md_file) {
    std::fprintf(stderr, "swf-eval: cannot write %s/results.md\n", out.c_str());
    return 1;
  }
  std::printf("swf-eval: wrote %s/results.md\n", out.c_str());
  return 0;
}
