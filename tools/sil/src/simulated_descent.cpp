#include "swf/sil/sil.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "swf/app/config.hpp"
#include "swf/app/config_fields.hpp"
#include "swf/evaluation/statistics.hpp"
#include "swf/hazard_eval/hazard_eval.hpp"
#include "swf/sim/rig.hpp"

namespace swf::sil {

namespace {

void PrintRenderProgress(int done, int total) {
  std::fprintf(stderr, "\rswf-sil: rendering the descent %d/%d", done, total);
  if (done == total) std::fprintf(stderr, "\n");
}

// Per output, as columns: frame, true altitude, errors, status and protection levels.
void WriteOutputs(std::FILE* f, const evaluation::RunScore& score) {
  bool first = true;
  const auto column = [&](const char* key, auto&& value) {
    std::fprintf(f, "%s\"%s\": [", first ? "" : ", ", key);
    first = false;
    for (std::size_t k = 0; k < score.outputs.size(); ++k)
      std::fprintf(f, "%s%s", k > 0 ? ", " : "", value(score.outputs[k]).c_str());
    std::fprintf(f, "]");
  };
  using Output = evaluation::OutputScore;
  std::fprintf(f, "  \"outputs\": {");
  column("frame", [](const Output& o) { return std::to_string(o.frame_seq); });
  column("altitude_m", [](const Output& o) { return app::JsonNumber(o.altitude_m); });
  column("horizontal_error_m",
         [](const Output& o) { return app::JsonNumber(o.horizontal_error_m); });
  column("vertical_error_m", [](const Output& o) { return app::JsonNumber(o.vertical_error_m); });
  column("attitude_error_deg",
         [](const Output& o) { return app::JsonNumber(o.attitude_error_deg); });
  column("status", [](const Output& o) { return std::to_string(o.status); });
  column("hpl_m", [](const Output& o) { return app::JsonNumber(o.hpl_m); });
  column("vpl_m", [](const Output& o) { return app::JsonNumber(o.vpl_m); });
  // Per world axis, to tell which direction a NEES outside its band comes from.
  const auto triple = [](const double* v) {
    std::string s = "[";
    for (int i = 0; i < 3; ++i) s.append(i > 0 ? ", " : "").append(app::JsonNumber(v[i]));
    return s.append("]");
  };
  column("position_error_m", [&](const Output& o) {
    const double e[3] = {o.estimate_m[0] - o.truth_m[0], o.estimate_m[1] - o.truth_m[1],
                         o.estimate_m[2] - o.truth_m[2]};
    return triple(e);
  });
  column("position_sigma_m", [&](const Output& o) { return triple(o.position_sigma_m); });
  std::fprintf(f, "},\n");
}

// The histogram of the signed errors (the paper's Fig. 2a): bins of kHistogramBinPx over
// [-kHistogramHalfWidthPx, kHistogramHalfWidthPx), the rest counted as outside.
constexpr double kHistogramBinPx = 0.05;
constexpr double kHistogramHalfWidthPx = 1.5;

// One signed error component as JSON: mean, sample standard deviation, robust sigma (1.4826 x
// the median absolute deviation), the fractions within 1, 2 and 3 standard deviations of the
// mean (a Gaussian: 0.683, 0.954, 0.997) and the histogram's counts.
std::string SignedErrorJson(const std::vector<double>& e) {
  const double mean = evaluation::Mean(e);
  const double std_px = evaluation::SampleStd(e);
  const double median = evaluation::Median(e);
  std::vector<double> deviation;
  deviation.reserve(e.size());
  for (double x : e) deviation.push_back(std::abs(x - median));
  const double robust = 1.4826 * evaluation::Median(deviation);
  double within[3] = {0.0, 0.0, 0.0};
  const int bins = static_cast<int>(std::lround(2.0 * kHistogramHalfWidthPx / kHistogramBinPx));
  std::vector<long long> counts(static_cast<std::size_t>(bins), 0);
  long long outside = 0;
  for (double x : e) {
    for (int k = 0; k < 3; ++k) within[k] += std::abs(x - mean) <= (k + 1) * std_px ? 1.0 : 0.0;
    const double b = std::floor((x + kHistogramHalfWidthPx) / kHistogramBinPx);
    if (b >= 0.0 && b < bins) {
      ++counts[static_cast<std::size_t>(b)];
    } else {
      ++outside;
    }
  }
  const double n = std::max<double>(1.0, static_cast<double>(e.size()));
  std::string counts_text;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    if (k > 0) counts_text += ", ";
    counts_text += std::to_string(counts[k]);
  }
  return "{\"mean\": " + app::JsonNumber(mean) + ", \"std\": " + app::JsonNumber(std_px) +
         ", \"robust_sigma\": " + app::JsonNumber(robust) +
         ", \"within_1_std\": " + app::JsonNumber(within[0] / n) +
         ", \"within_2_std\": " + app::JsonNumber(within[1] / n) +
         ", \"within_3_std\": " + app::JsonNumber(within[2] / n) +
         ", \"outside_histogram\": " + std::to_string(outside) + ", \"counts\": [" + counts_text +
         "]}";
}

// The standard deviation a measurement with these errors has under the filter's Huber weights
// (threshold k times it): the M-estimator's asymptotic variance E[psi(e)^2] / E[psi'(e)]^2,
// psi(e) = clamp(e, -c, c), c = k x the result (fixed point; docs/imu.md, "The measurement
// sigma"). NaN for an empty list.
double HuberEffectiveSigma(const std::vector<double>& e, double k = 3.5) {
  if (e.empty()) return NAN;
  double sigma = std::max(1e-3, evaluation::Rms(e));
  for (int it = 0; it < 100; ++it) {
    const double c = k * sigma;
    double psi2 = 0.0;
    double inside = 0.0;
    for (double x : e) {
      psi2 += std::min(std::abs(x), c) * std::min(std::abs(x), c);
      inside += std::abs(x) < c ? 1.0 : 0.0;
    }
    if (inside <= 0.0) return NAN;
    sigma = 0.5 * sigma + 0.5 * std::sqrt(psi2 / static_cast<double>(e.size())) /
                              (inside / static_cast<double>(e.size()));
  }
  return sigma;
}

// The signed u and v errors grouped by one property of the measurement (bins [edges[i],
// edges[i+1])): per bin the count, the median radial fraction (TrackingErrors), the errors'
// Huber-effective sigma in pixels and that of the errors divided by the sigma the filter was told
// (1 for a measurement model that fits).
std::string BinnedErrorsJson(const Evaluation::TrackingErrors& t,
                             const std::vector<double>& property,
                             const std::vector<double>& edges) {
  std::string text = "[";
  for (std::size_t b = 0; b + 1 < edges.size(); ++b) {
    std::vector<double> px;
    std::vector<double> normalized;
    std::vector<double> radial;
    for (std::size_t i = 0; i < property.size(); ++i) {
      if (!(property[i] >= edges[b] && property[i] < edges[b + 1])) continue;
      if (std::isfinite(t.radial_fraction[i])) radial.push_back(t.radial_fraction[i]);
      px.push_back(t.du_px[i]);
      px.push_back(t.dv_px[i]);
      if (t.stated_sigma_px[i] > 0.0) {
        normalized.push_back(t.du_px[i] / t.stated_sigma_px[i]);
        normalized.push_back(t.dv_px[i] / t.stated_sigma_px[i]);
      }
    }
    if (b > 0) text += ", ";
    text +=
        "{\"from\": " + app::JsonNumber(edges[b]) + ", \"to\": " + app::JsonNumber(edges[b + 1]) +
        ", \"measurements\": " + std::to_string(px.size() / 2) +
        ", \"radial_fraction_median\": " + app::JsonNumber(evaluation::Median(radial)) +
        ", \"huber_sigma_px\": " + app::JsonNumber(HuberEffectiveSigma(px)) +
        ", \"normalized_huber_sigma\": " + app::JsonNumber(HuberEffectiveSigma(normalized)) + "}";
  }
  return text + "]";
}

// The tracking errors by track age (frames since the first sighting), by the true magnification
// since then, and by the true altitude: where the front end's error grows.
void WriteTrackingErrorBins(std::FILE* f, const Evaluation::TrackingErrors& t) {
  const std::vector<double> age(t.age.begin(), t.age.end());
  std::fprintf(
      f,
      "  \"tracking_error_bins\": {\"by_age\": %s,\n    \"by_magnification\": %s,\n    "
      "\"by_altitude_m\": %s,\n    \"by_relief_fraction\": %s},\n",
      BinnedErrorsJson(t, age, {1, 2, 3, 4, 6, 9, 13, 17, 25, 1e9}).c_str(),
      BinnedErrorsJson(t, t.magnification,
                       {0.0, 1.02, 1.05, 1.1, 1.2, 1.35, 1.5, 1.75, 2.0, 2.5, 1e9})
          .c_str(),
      BinnedErrorsJson(t, t.altitude_m, {0, 15, 20, 30, 40, 50, 60, 70, 80, 90, 1e9}).c_str(),
      BinnedErrorsJson(t, t.relief_fraction, {-1e9, -2e-3, -5e-4, -1e-4, 1e-4, 5e-4, 2e-3, 1e9})
          .c_str());
}

// The correlation of two error components over the pairs inside the filter's Huber threshold
// (3.5 of each one's Huber-effective sigma): what the weights keep. NaN below 3 such pairs.
double InlierCorrelation(const std::vector<double>& a, const std::vector<double>& b) {
  const double ca = 3.5 * HuberEffectiveSigma(a);
  const double cb = 3.5 * HuberEffectiveSigma(b);
  std::vector<double> x;
  std::vector<double> y;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(std::abs(a[i]) < ca && std::abs(b[i]) < cb)) continue;
    x.push_back(a[i]);
    y.push_back(b[i]);
  }
  if (x.size() < 3) return NAN;
  const double mx = evaluation::Mean(x);
  const double my = evaluation::Mean(y);
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxx > 0.0 && syy > 0.0 ? sxy / std::sqrt(sxx * syy) : NAN;
}

// The fraction of errors beyond k times their Huber-effective sigma (a Gaussian: 5.7e-7 at 5):
// the tail that a sigma fitted to the core does not state.
double TailFraction(const std::vector<double>& e, double k) {
  const double limit = k * HuberEffectiveSigma(e);
  if (e.empty() || !std::isfinite(limit)) return NAN;
  double beyond = 0.0;
  for (double x : e) beyond += std::abs(x) > limit ? 1.0 : 0.0;
  return beyond / static_cast<double>(e.size());
}

// The stereo errors grouped by one property (bins [edges[i], edges[i+1])): per bin the count,
// the Huber-effective sigma of the left u, the right u and the disparity errors, the disparity
// error's median (a bias places every landmark of the bin at a wrong depth) and tail, the inlier
// correlation of the left error with the right one and with the disparity's, and the disparity
// error over the disparity sigma the filter was told.
std::string BinnedStereoErrorsJson(const Evaluation::StereoErrors& t,
                                   const std::vector<double>& property,
                                   const std::vector<double>& edges) {
  std::string text = "[";
  for (std::size_t b = 0; b + 1 < edges.size(); ++b) {
    std::vector<double> left, right, disparity, normalized, drift;
    for (std::size_t i = 0; i < property.size(); ++i) {
      if (!(property[i] >= edges[b] && property[i] < edges[b + 1])) continue;
      if (std::isfinite(t.depth_drift_fraction[i])) drift.push_back(t.depth_drift_fraction[i]);
      left.push_back(t.du_left_px[i]);
      right.push_back(t.du_right_px[i]);
      disparity.push_back(t.dd_px[i]);
      if (t.stated_sigma_disparity_px[i] > 0.0)
        normalized.push_back(t.dd_px[i] / t.stated_sigma_disparity_px[i]);
    }
    if (b > 0) text += ", ";
    text +=
        "{\"from\": " + app::JsonNumber(edges[b]) + ", \"to\": " + app::JsonNumber(edges[b + 1]) +
        ", \"measurements\": " + std::to_string(left.size()) +
        ", \"left_huber_sigma_px\": " + app::JsonNumber(HuberEffectiveSigma(left)) +
        ", \"right_huber_sigma_px\": " + app::JsonNumber(HuberEffectiveSigma(right)) +
        ", \"disparity_huber_sigma_px\": " + app::JsonNumber(HuberEffectiveSigma(disparity)) +
        ", \"disparity_median_px\": " + app::JsonNumber(evaluation::Median(disparity)) +
        ", \"depth_drift_fraction_median\": " + app::JsonNumber(evaluation::Median(drift)) +
        ", \"disparity_beyond_5_sigma\": " + app::JsonNumber(TailFraction(disparity, 5.0)) +
        ", \"left_right_correlation\": " + app::JsonNumber(InlierCorrelation(left, right)) +
        ", \"left_disparity_correlation\": " + app::JsonNumber(InlierCorrelation(left, disparity)) +
        ", \"disparity_normalized_huber_sigma\": " +
        app::JsonNumber(HuberEffectiveSigma(normalized)) + "}";
  }
  return text + "]";
}

// How alike a track's errors are in consecutive frames, by its age (bins [edges[i],
// edges[i+1])): the inlier correlation of the left u error and of the disparity error with the
// frame before's. The filter takes them as independent; near 1 a window of K frames holds
// about one measurement's worth of that error, not K.
std::string FrameToFrameJson(const Evaluation::StereoErrors& t, const std::vector<int>& edges) {
  std::string text = "[";
  for (std::size_t b = 0; b + 1 < edges.size(); ++b) {
    std::vector<double> left_then, left_now, disparity_then, disparity_now;
    for (std::size_t i = 0; i < t.pair_age.size(); ++i) {
      if (!(t.pair_age[i] >= edges[b] && t.pair_age[i] < edges[b + 1])) continue;
      left_then.push_back(t.left_then_px[i]);
      left_now.push_back(t.left_now_px[i]);
      disparity_then.push_back(t.disparity_then_px[i]);
      disparity_now.push_back(t.disparity_now_px[i]);
    }
    if (b > 0) text += ", ";
    text += "{\"from_age\": " + std::to_string(edges[b]) +
            ", \"to_age\": " + std::to_string(edges[b + 1]) +
            ", \"pairs\": " + std::to_string(left_now.size()) +
            ", \"left_correlation\": " + app::JsonNumber(InlierCorrelation(left_then, left_now)) +
            ", \"disparity_correlation\": " +
            app::JsonNumber(InlierCorrelation(disparity_then, disparity_now)) + "}";
  }
  return text + "]";
}

// The stereo match's own error (Evaluation::Stereo) beside the left image's
// (tracking_error_bins): by track age (0: the first sighting), by the true magnification, by the
// true altitude, by the true disparity (the landmark's range) and by the match's ZNCC (all, and
// the first sightings alone).
void WriteDisparityErrorBins(std::FILE* f, const Evaluation::StereoErrors& t) {
  const std::vector<double> age(t.age.begin(), t.age.end());
  std::vector<double> first_quality = t.quality;
  for (std::size_t i = 0; i < first_quality.size(); ++i)
    if (t.age[i] != 0) first_quality[i] = NAN;
  const std::vector<double> quality_edges = {-1.0, 0.8, 0.85, 0.9, 0.95, 0.97, 0.98, 0.99, 1.01};
  std::fprintf(
      f,
      "  \"disparity_error_bins\": {\"by_age\": %s,\n    \"by_magnification\": %s,\n    "
      "\"by_altitude_m\": %s,\n    \"by_true_disparity_px\": %s,\n    \"by_quality\": %s,\n    "
      "\"first_sighting_by_quality\": %s,\n    \"by_left_subpixel_phase\": %s,\n    \"all\": %s,\n "
      "   "
      "\"frame_to_frame\": %s},\n",
      BinnedStereoErrorsJson(t, age, {0, 1, 2, 4, 8, 16, 1e9}).c_str(),
      BinnedStereoErrorsJson(t, t.magnification,
                             {0.0, 1.02, 1.05, 1.1, 1.2, 1.35, 1.5, 1.75, 2.0, 2.5, 1e9})
          .c_str(),
      BinnedStereoErrorsJson(t, t.altitude_m, {0, 15, 20, 30, 40, 50, 60, 70, 80, 90, 1e9}).c_str(),
      BinnedStereoErrorsJson(t, t.true_disparity_px, {0, 15, 20, 30, 40, 60, 80, 120, 160, 1e9})
          .c_str(),
      BinnedStereoErrorsJson(t, t.quality, quality_edges).c_str(),
      BinnedStereoErrorsJson(t, first_quality, quality_edges).c_str(),
      BinnedStereoErrorsJson(t, t.left_subpixel_phase, {0.0, 0.2, 0.4, 0.6, 0.8, 1.0}).c_str(),
      BinnedStereoErrorsJson(t, t.altitude_m, {-1e9, 1e9}).c_str(),
      FrameToFrameJson(t, {1, 2, 4, 8, 16, 1000000000}).c_str());
}

// One hazard map's evaluation as a JSON object (without the safe site of the final map).
// The front end's measurements against the renderer's truth (Evaluation::Tracking): every fused
// measurement of a known landmark, and the landmarks of the first frame, overall and once they
// are 10 frames old (their drift); the signed components with their histogram.
void WriteTrackingErrors(std::FILE* f, const Evaluation::TrackingErrors& t) {
  std::vector<double> old_px;
  for (std::size_t i = 0; i < t.first_frame_px.size(); ++i) {
    if (t.first_frame_age[i] >= 10) old_px.push_back(t.first_frame_px[i]);
  }
  std::fprintf(
      f,
      "  \"tracking_error_px\": {\"measurements\": %zu, \"median\": %s, \"p90\": %s, "
      "\"rms\": %s,\n    \"first_frame\": {\"measurements\": %zu, \"median\": %s, "
      "\"p90\": %s, \"measurements_10_frames_old\": %zu, \"median_10_frames_old\": %s},\n"
      "    \"signed\": {\"bin_px\": %.3f, \"first_bin_px\": %.3f,\n      \"u\": %s,\n      "
      "\"v\": %s}},\n",
      t.all_px.size(), app::JsonNumber(evaluation::Median(t.all_px)).c_str(),
      app::JsonNumber(evaluation::Quantile(t.all_px, 0.9)).c_str(),
      app::JsonNumber(evaluation::Rms(t.all_px)).c_str(), t.first_frame_px.size(),
      app::JsonNumber(evaluation::Median(t.first_frame_px)).c_str(),
      app::JsonNumber(evaluation::Quantile(t.first_frame_px, 0.9)).c_str(), old_px.size(),
      app::JsonNumber(evaluation::Median(old_px)).c_str(), kHistogramBinPx, -kHistogramHalfWidthPx,
      SignedErrorJson(t.du_px).c_str(), SignedErrorJson(t.dv_px).c_str());
}

// Every published landmark map's error against the truth, in frame order (the image-level
// counterpart of the landmark-error curves of the paper's Figs. 12 and 13).
void WriteLandmarkMaps(std::FILE* f, const std::vector<evaluation::MapScore>& maps) {
  std::string frame;
  std::string evaluated;
  std::string rms;
  for (std::size_t k = 0; k < maps.size(); ++k) {
    if (k > 0) {
      frame += ", ";
      evaluated += ", ";
      rms += ", ";
    }
    frame += std::to_string(maps[k].frame_seq);
    evaluated += std::to_string(maps[k].landmarks_evaluated);
    rms += app::JsonNumber(maps[k].rms_error_m);
  }
  std::fprintf(f,
               "  \"landmark_maps_by_frame\": {\"frame\": [%s],\n    \"landmarks_evaluated\": "
               "[%s],\n    \"rms_error_m\": [%s]},\n",
               frame.c_str(), evaluated.c_str(), rms.c_str());
}

// The last map's landmarks against their stated covariances: the NEES's median and mean (3 for
// a consistent map), and the worst landmarks by error with their error (world axes; the descent
// looks down, so z is mostly the depth), stated 1-sigma per axis, NEES, observations in the
// window and first-sighting frame: whether a map's RMS is its bulk or a few landmarks.
void WriteLastMapLandmarks(std::FILE* f, const std::vector<evaluation::LandmarkScore>& last,
                           const Evaluation& evaluation, int worst) {
  std::vector<double> nees;
  for (const evaluation::LandmarkScore& l : last)
    if (std::isfinite(l.nees)) nees.push_back(l.nees);
  std::vector<const evaluation::LandmarkScore*> order;
  for (const evaluation::LandmarkScore& l : last) order.push_back(&l);
  std::sort(order.begin(), order.end(),
            [](const auto* a, const auto* b) { return a->error_m > b->error_m; });
  std::string text;
  for (int k = 0; k < worst && k < static_cast<int>(order.size()); ++k) {
    const evaluation::LandmarkScore& l = *order[static_cast<std::size_t>(k)];
    app::NewSighting first;
    const bool seen = evaluation.FirstSeen(l.id, &first);
    const double* c = l.covariance_m2;
    std::string error;
    std::string sigma;
    const double variance[3] = {c[0], c[3], c[5]};
    for (int i = 0; i < 3; ++i) {
      if (i > 0) {
        error += ", ";
        sigma += ", ";
      }
      error += app::JsonNumber(l.estimate_m[i] - l.truth_m[i]);
      sigma += app::JsonNumber(std::sqrt(std::max(0.0, variance[i])));
    }
    if (k > 0) text += ",\n      ";
    text += "{\"id\": " + std::to_string(l.id) + ", \"error_m\": " + app::JsonNumber(l.error_m) +
            ", \"error_world_m\": [" + error + "], \"sigma_world_m\": [" + sigma +
            "], \"nees\": " + app::JsonNumber(l.nees) +
            ", \"observations\": " + std::to_string(l.num_observations) +
            ", \"first_frame\": " + (seen ? std::to_string(first.frame_seq) : "null") + "}";
  }
  std::fprintf(f,
               "  \"last_map_landmarks\": {\"nees_median\": %s, \"nees_mean\": %s, "
               "\"worst\": [\n      %s]},\n",
               app::JsonNumber(evaluation::Median(nees)).c_str(),
               app::JsonNumber(evaluation::Mean(nees)).c_str(), text.c_str());
}

void WriteHazardEvaluation(std::FILE* f, const evaluation::HazardScore& e) {
  const evaluation::HazardMapMetrics& h = e.map;
  std::fprintf(
      f,
      "{\"frame\": %lld, \"altitude_m\": %s, \"known_cells\": %d, "
      "\"rocks_resolved\": %d, \"rocks_detected\": %d, \"detection_probability\": %s, "
      "\"rocks_resolved_by_height\": [%d, %d, %d], "
      "\"rocks_detected_by_height\": [%d, %d, %d], \"rock_free_cells\": %d, "
      "\"false_rock_cells\": %d, \"false_alarm_rate\": %.5f, \"site_on_truth_hazard\": %s}",
      static_cast<long long>(e.frame_seq), app::JsonNumber(e.altitude_m).c_str(), h.known_cells,
      h.rocks_resolved, h.rocks_detected,
      h.detection_probability >= 0.0 ? app::JsonNumber(h.detection_probability).c_str() : "null",
      h.rocks_resolved_by_height[0], h.rocks_resolved_by_height[1], h.rocks_resolved_by_height[2],
      h.rocks_detected_by_height[0], h.rocks_detected_by_height[1], h.rocks_detected_by_height[2],
      h.rock_free_cells, h.false_rock_cells, h.false_alarm_rate,
      !h.site_valid ? "null" : (h.site_on_hazard ? "true" : "false"));
}

// The hazard maps: the final one with its safe site, and every one by altitude. The height
// classes are [1, 2), [2, 4), [4, inf) times the rock threshold (hazard.max_rock_height_m).
void WriteHazardMaps(std::FILE* f, const std::vector<evaluation::HazardScore>& evals) {
  std::fprintf(f, "  \"hazard\": ");
  WriteHazardEvaluation(f, evals.back());
  std::fprintf(f, ",\n  \"hazard_by_map\": [");
  for (std::size_t k = 0; k < evals.size(); ++k) {
    std::fprintf(f, "%s\n    ", k > 0 ? "," : "");
    WriteHazardEvaluation(f, evals[k]);
  }
  std::fprintf(f, "],\n");
  const evaluation::HazardMapMetrics& h = evals.back().map;
  if (h.site_valid) {
    std::fprintf(f,
                 "  \"safe_site\": {\"x_m\": %.3f, \"y_m\": %.3f, \"score\": %.4f, "
                 "\"clearance_to_truth_hazard_m\": %.3f, \"on_truth_hazard\": %s}\n",
                 h.site_world_m[0], h.site_world_m[1], h.site_score, h.site_clearance_m,
                 h.site_on_hazard ? "true" : "false");
  } else {
    std::fprintf(f, "  \"safe_site\": null\n");
  }
}

}  // namespace

void SimulatedDescent::DrawPlots(const std::string& dir, const app::MapperHazardStage& hazard,
                                 app::Verdict* verdict) const {
  // The picture of what guidance received: the last published map, not the mapper's state.
  const app::HazardRecord* last = evaluation_.LastHazardMap();
  const evaluation::HazardMapView view =
      last != nullptr ? hazard_eval::ViewOf(*last) : evaluation::HazardMapView{};
  plot::RunPictures pictures;
  pictures.last_hazard_map = last != nullptr ? &view : nullptr;
  pictures.footprint_radius_m = hazard.Mapper().Options().footprint_radius_m;
  std::vector<std::string> errors;
  (void)plot::DrawRun(score_, pictures, dir, &errors);
  const plot::HeightGrid terrain = evaluation_.TerrainTruth();
  const sim::Trajectory& trajectory = world_->Trajectory();
  if (terrain.size > 0 && trajectory.NumFrames() > 0) {
    const double target[2] = {trajectory.WorldTCamera(0).t.x(), trajectory.WorldTCamera(0).t.y()};
    std::string error;
    if (!plot::DrawTerrainHazard(terrain, true, target,
                                 "Terrain '" + config_->sim.terrain + "' and its hazard truth",
                                 dir + "/terrain_hazard.png", &error))
      errors.push_back(error);
  }
  for (const std::string& e : errors) {
    std::fprintf(stderr, "swf-sil: cannot draw %s\n", e.c_str());
    app::Fail(verdict, "summary.plot_dir: cannot draw " + e);
  }
}

const app::ConfigExtension* SimulatedDescent::Config() const { return SimConfigExtension(); }

bool SimulatedDescent::OpenSource(const app::FswConfig& config, bool progress,
                                  app::PipelineOptions* po,
                                  std::unique_ptr<drivers::StereoSource>* source,
                                  std::int64_t* total_frames, std::string* error) {
  config_ = &config;
  world_ = std::make_unique<SimWorld>();
  SimWorld& world = *world_;
  std::fprintf(stderr, "swf-sil: building the simulated world (terrain %s, %dx%d px) ...\n",
               config.sim.terrain.c_str(), config.sim.width_px, config.sim.height_px);
  if (!world.Build(config, error) ||
      !world.RenderAll(config.sim.render_threads, progress ? PrintRenderProgress : nullptr,
                       error)) {
    return false;
  }
  if (config.initial == "truth") {
    SimHandover(config, world.Trajectory(), po);
  } else {
    po->imu = SimImuOptions(config, nullptr);
  }
  if (config.sim.target == "orbital") {
    const sim::OrbitalTarget& t = world.Target();
    std::fprintf(stderr,
                 "swf-sil: orbital target (%.1f, %.1f) m, %.1f m from the nominal, orbital "
                 "clearance %.1f m\n",
                 t.target_m.x(), t.target_m.y(), t.distance_m, t.clearance_m);
  }
  po->camera = world.Camera();
  po->width_px = world.Width();
  po->height_px = world.Height();
  *total_frames = world.DeliveredFrames();
  *source = std::make_unique<sim::PrerenderedStereoSource>(&world.Frames());
  return true;
}

bool SimulatedDescent::Start(const app::FswConfig& config, app::PipelineOptions* po,
                             std::string* error) {
  if (config.initial != "truth") {
    po->imu = SimImuOptions(config, nullptr);
    return true;
  }
  sim::Trajectory trajectory;
  sim::RigOptions rig;
  if (!SimTrajectory(config, &trajectory, &rig, error)) return false;
  SimHandover(config, trajectory, po);
  return true;
}

estimator::StereoCamera<double> SimulatedDescent::RectifiedRig(const app::FswConfig& config,
                                                               int width_px, int height_px) {
  sim::RigOptions rig = SimRig(config);
  rig.width_px = width_px;
  rig.height_px = height_px;
  return sim::MakeStereoCamera(rig);
}

drivers::MotionProvider* SimulatedDescent::Motion() { return world_.get(); }
drivers::ImuProvider* SimulatedDescent::Imu() { return world_.get(); }

void SimulatedDescent::Observe(app::FlightParts* parts) {
  evaluation_.Attach(&world_->Trajectory(), &world_->Terrain(), world_->Camera(),
                     parts->hazard->Mapper().Options(), &parts->output);
}

void SimulatedDescent::Evaluate(const app::FswConfig& config, const app::FlightParts& parts,
                                const app::PipelineOptions& po, std::int64_t imu_samples_taken,
                                app::Verdict* verdict, app::ImuReport* imu) {
  const SimWorld& world = *world_;
  score_ = evaluation_.Score();
  if (parts.pipeline) frontend_ = parts.pipeline->Frontend();
  if (!config.plot_dir.empty()) DrawPlots(config.plot_dir, *parts.hazard, verdict);
  if (score_.protection_violations > 0) {
    app::Fail(verdict, std::to_string(score_.protection_violations) +
                           " VALID outputs erred beyond their protection level");
  }
  // The unit's true bias at the last sample the pipeline took.
  const sim::ImuModel* unit = world.ImuUnit();
  if (imu != nullptr && unit != nullptr && imu_samples_taken > 0 &&
      imu_samples_taken <= static_cast<std::int64_t>(unit->TrueBiases().size())) {
    imu->has_truth = true;
    imu->truth = unit->TrueBiases()[static_cast<std::size_t>(imu_samples_taken - 1)];
    imu->imu_only_pose_rms_m =
        ImuOnlyPoseRms(*unit, world.Trajectory(), po.imu, po.initial_world_T_camera);
  }
}

std::string SimulatedDescent::RunLine() const {
  char text[160];
  if (LandmarksEvaluated() > 0) {
    std::snprintf(text, sizeof text, ", landmark RMS error %.3f m, pose RMS error %.3f m",
                  score_.maps.back().rms_error_m, score_.pose_rms_error_m);
  } else {
    std::snprintf(text, sizeof text, ", no landmark map to evaluate, pose RMS error %.3f m",
                  score_.pose_rms_error_m);
  }
  return text;
}

std::int64_t SimulatedDescent::LandmarksEvaluated() const {
  return score_.maps.empty() ? 0 : score_.maps.back().landmarks_evaluated;
}

void SimulatedDescent::WriteSummaryHead(std::FILE* f) const {
  const app::FswConfig& c = *config_;
  std::fprintf(f, "  \"image_width_px\": %d,\n  \"image_height_px\": %d,\n", c.sim.width_px,
               c.sim.height_px);
  std::fprintf(f, "  \"terrain\": \"%s\",\n  \"seed\": %llu,\n", c.sim.terrain.c_str(),
               static_cast<unsigned long long>(c.sim.seed));
  // Where the simulated descent went: the nadir of the first frame, and for `sim.target:
  // orbital` the pre-selection's clearance from orbit-visible hazards.
  const sim::Trajectory& trajectory = world_->Trajectory();
  if (trajectory.NumFrames() > 0) {
    const Eigen::Vector3d& p = trajectory.WorldTCamera(0).t;
    std::fprintf(f, "  \"descent_target\": {\"mode\": \"%s\", \"x_m\": %.3f, \"y_m\": %.3f",
                 c.sim.target.c_str(), p.x(), p.y());
    if (c.sim.target == "orbital") {
      const sim::OrbitalTarget& target = world_->Target();
      std::fprintf(f,
                   ", \"search_radius_m\": %.1f, \"orbital_clearance_m\": %.3f, "
                   "\"distance_from_nominal_m\": %.3f",
                   c.sim.target_search_m, target.clearance_m, target.distance_m);
    }
    std::fprintf(f, "},\n");
  }
  const evaluation::RunScore& score = score_;
  // Landmark errors come from the last published landmark map; with none evaluated they are
  // null, not a perfect 0.
  if (LandmarksEvaluated() > 0) {
    std::fprintf(f, "  \"landmark_rms_error_m\": %.6f,\n  \"landmark_median_error_m\": %.6f,\n",
                 score.maps.back().rms_error_m, score.maps.back().median_error_m);
  } else {
    std::fprintf(f, "  \"landmark_rms_error_m\": null,\n  \"landmark_median_error_m\": null,\n");
  }
  std::fprintf(
      f,
      "  \"landmarks_evaluated\": %lld,\n  \"pose_rms_error_m\": %s,\n"
      "  \"final_pose_error_m\": %.6f,\n  \"nav_outputs\": %lld,\n"
      "  \"landmark_maps\": %lld,\n",
      static_cast<long long>(LandmarksEvaluated()),
      (std::isfinite(score.pose_rms_error_m) ? app::Fixed(score.pose_rms_error_m, 6) : "null")
          .c_str(),
      score.final_pose_error_m, static_cast<long long>(score.outputs.size()),
      static_cast<long long>(score.maps.size()));
  WriteTrackingErrors(f, evaluation_.Tracking());
  WriteTrackingErrorBins(f, evaluation_.Tracking());
  WriteDisparityErrorBins(f, evaluation_.Stereo());
  WriteLandmarkMaps(f, score.maps);
  WriteLastMapLandmarks(f, score.last_map, evaluation_, 8);
  const app::FrontendCounters& fc = frontend_;
  std::fprintf(f,
               "  \"frontend\": {\"refine_in_loop\": %s, \"reference_from_estimate\": %s, "
               "\"recover_lost_tracks\": %s, \"measurements\": %lld, \"warped\": %lld, "
               "\"lost_tracking\": %lld, \"searched\": %lld, \"recovered\": %lld, "
               "\"recovered_inconsistent\": %lld, "
               "\"rejected_consistency\": %lld, \"refined\": %lld},\n",
               c.frontend_refine_in_loop ? "true" : "false",
               c.frontend_reference_from_estimate ? "true" : "false",
               c.frontend_recover_lost_tracks ? "true" : "false",
               static_cast<long long>(fc.measurements), static_cast<long long>(fc.warped),
               static_cast<long long>(fc.lost_tracking), static_cast<long long>(fc.searched),
               static_cast<long long>(fc.recovered),
               static_cast<long long>(fc.recovered_inconsistent),
               static_cast<long long>(fc.rejected_consistency), static_cast<long long>(fc.refined));
  std::fprintf(f, "  \"mean_position_nees\": %s,\n  \"position_nees\": [",
               app::JsonNumber(score.mean_position_nees).c_str());
  for (std::size_t k = 0; k < score.outputs.size(); ++k) {
    std::fprintf(f, "%s%s", k > 0 ? ", " : "",
                 app::JsonNumber(score.outputs[k].position_nees).c_str());
  }
  std::fprintf(f, "],\n  \"final_attitude_error_deg\": %s,\n",
               app::JsonNumber(score.final_attitude_error_deg).c_str());
  WriteOutputs(f, score);
}

void SimulatedDescent::WriteIntegrityTruth(std::FILE* f) const {
  std::fprintf(f,
               ", \"valid_outputs_vs_truth\": %lld, \"protection_violations\": %lld, "
               "\"max_error_over_protection\": %.4f",
               static_cast<long long>(score_.valid_navs),
               static_cast<long long>(score_.protection_violations),
               score_.max_error_over_protection);
}

bool SimulatedDescent::WriteHazardTruth(std::FILE* f) const {
  if (score_.hazard_maps.empty()) return false;
  WriteHazardMaps(f, score_.hazard_maps);
  return true;
}

}  // namespace swf::sil
