#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace swf::eval {
namespace {

// Ten evenly spaced frames and the last: where a long run's error grew.
Json Checkpoints(const RunRecord& run, const StereoSequence& s) {
  const std::size_t n = run.frames.size();
  std::vector<std::size_t> frames;
  for (int k = 1; k <= 10; ++k) frames.push_back(std::min(n - 1, k * n / 10));
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  Json checkpoints = Json::array();
  for (const std::size_t j : frames) {
    const FrameRecord& f = run.frames[j];
    Json o = {{"frame", j}};
    SetNumber(&o, "t_s", 1e-9 * static_cast<double>(s.frames[j].stamp_ns - s.frames[0].stamp_ns));
    SetNumber(&o, "anchored_error_m", f.anchored_error_m);
    SetNumber(&o, "position_sigma_m", f.position_sigma_m);
    o["tracked"] = f.tracked;
    o["window_measurements"] = f.window_measurements;
    o["fault_bits"] = f.fault_bits;
    o["integrity"] = f.integrity;
    SetNumber(&o, "hpl_m", f.hpl_m);
    SetNumber(&o, "vpl_m", f.vpl_m);
    checkpoints.push_back(o);
  }
  return checkpoints;
}

// What the navigation output claimed against what the truth says: frames per status, and frames
// whose error exceeded a protection level (misleading when the status was VALID).
Json IntegrityJson(const RunRecord& run) {
  return {{"frames_valid", run.frames_by_integrity[0]},
          {"frames_degraded", run.frames_by_integrity[1]},
          {"frames_invalid", run.frames_by_integrity[2]},
          {"misleading_frames", run.misleading_frames},
          {"first_misleading_frame", run.first_misleading_frame},
          {"degraded_beyond_protection", run.degraded_beyond_protection}};
}

std::string Verdicted(const RunRecord& run) {
  return run.options.name + " " + ToString(run.verdict);
}

}  // namespace

std::string Format(const char* format, ...) {
  char buf[4096];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof(buf), format, args);
  va_end(args);
  return buf;
}

bool AllOk(const std::vector<RunRecord>& runs) {
  return std::all_of(runs.begin(), runs.end(), [](const RunRecord& r) { return r.Ok(); });
}

Json RunJson(const RunRecord& run, const StereoSequence& sequence, const std::string& trajectory) {
  const TrajectoryErrors& e = run.errors;
  // A failed run has no score: its numbers would rank a broken run (a still estimate without
  // measurements scores well on a still camera).
  const std::string why =
      run.Ok() ? "" : "no score: " + std::string(ToString(run.verdict)) + ", " + run.reason;
  Json o = {{"name", run.options.name},
            {"status", ToString(run.verdict)},
            {"window", run.options.window},
            {"frames", run.frames.size()}};
  auto score = [&](const char* key, double value) {
    if (run.Ok()) {
      SetNumber(&o, key, value, e.finite ? "" : e.reason);
    } else {
      SetNull(&o, key, why);
    }
  };
  if (!run.Ok()) {
    o["reason"] = run.reason;
    o["failure_frame"] = run.failure_frame;
  }
  score("ate_rmse_m", e.ate_rmse_m);
  score("ate_max_m", e.ate_max_m);
  score("final_error_m", e.final_aligned_error_m);
  score("final_anchored_error_m", e.final_anchored_error_m);
  score("step_translation_mean_m", e.step_translation_mean_m);
  score("step_translation_max_m", e.step_translation_max_m);
  score("step_rotation_mean_deg", e.step_rotation_mean_deg);
  score("step_rotation_max_deg", e.step_rotation_max_deg);
  if (run.Ok() && !std::isfinite(e.step_translation_percent) && e.finite) {
    SetNull(&o, "step_translation_percent", "the truth moved less than 1 cm: no percentage");
    SetNull(&o, "step_rotation_deg_per_m", "the truth moved less than 1 cm: no rate per metre");
  } else {
    score("step_translation_percent", e.step_translation_percent);
    score("step_rotation_deg_per_m", e.step_rotation_deg_per_m);
  }
  // Not scores but what happened: kept for failed runs too (null when not finite).
  SetNumber(&o, "max_anchored_error_m", e.max_anchored_error_m,
            e.finite ? "" : "not computed: " + e.reason);
  o["update_failures"] = run.estimate_failures;
  o["frames_without_tracks"] = run.frames_without_tracks;
  SetNumber(&o, "tracked_per_frame", run.mean_tracked, "no frame was processed");
  SetNumber(&o, "seconds", run.seconds);
  o["integrity"] = IntegrityJson(run);
  if (run.options.imu) {
    Json imu = {{"samples_accepted", run.imu_samples_accepted},
                {"samples_dropped", run.imu_samples_dropped},
                {"intervals_bridged", run.imu_intervals_bridged}};
    if (run.has_biases) {
      const Vec3D& g = run.gyro_bias_radps;
      const Vec3D& a = run.accel_bias_mps2;
      imu["gyro_bias_radps"] = Numbers({g.x(), g.y(), g.z()});
      imu["accel_bias_mps2"] = Numbers({a.x(), a.y(), a.z()});
    }
    o["imu"] = imu;
  }
  if (!trajectory.empty()) o["trajectory"] = trajectory;
  if (!run.frames.empty()) o["checkpoints"] = Checkpoints(run, sequence);
  return o;
}

std::string RunsTable(const std::vector<RunRecord>& runs) {
  std::string t =
      "| run | status | ATE RMSE (m) | last frame, no fit (m) | per-frame translation error "
      "mean / max (m) | per-frame rotation error mean / max (deg) | tracked/frame |\n"
      "|---|---|---|---|---|---|---|\n";
  for (const RunRecord& r : runs) {
    const TrajectoryErrors& e = r.errors;
    if (r.Ok()) {
      t += Format("| %s | ok | %.4f | %.4f | %.4f / %.4f | %.3f / %.3f | %.0f |\n",
                  r.options.name.c_str(), e.ate_rmse_m, e.final_anchored_error_m,
                  e.step_translation_mean_m, e.step_translation_max_m, e.step_rotation_mean_deg,
                  e.step_rotation_max_deg, r.mean_tracked);
    } else {
      t += Format("| %s | **%s** at frame %d | - | - | - | - | %.0f |\n", r.options.name.c_str(),
                  ToString(r.verdict), r.failure_frame, r.mean_tracked);
    }
  }
  return t;
}

std::string CompareSentence(const RunRecord& a, double value_a, const RunRecord& b, double value_b,
                            const std::string& what) {
  if (!a.Ok() && !b.Ok()) {
    return Format("Neither run is scored (%s, %s), so their %s is not compared.",
                  Verdicted(a).c_str(), Verdicted(b).c_str(), what.c_str());
  }
  if (!a.Ok() || !b.Ok()) {
    const RunRecord& bad = a.Ok() ? b : a;
    const RunRecord& good = a.Ok() ? a : b;
    return Format("%s is not scored (%s), so its %s is not compared with %s's (%.4g m).",
                  bad.options.name.c_str(), ToString(bad.verdict), what.c_str(),
                  good.options.name.c_str(), a.Ok() ? value_a : value_b);
  }
  if (!(value_a >= 0.0 && value_b >= 0.0 && std::isfinite(value_a) && std::isfinite(value_b))) {
    return Format("The %s of %s or %s is not a finite number: not compared.", what.c_str(),
                  a.options.name.c_str(), b.options.name.c_str());
  }
  const std::string head = Format("%s %s %.4g m against %s %.4g m", a.options.name.c_str(),
                                  what.c_str(), value_a, b.options.name.c_str(), value_b);
  const double ratio = value_a / std::max(value_b, 1e-300);
  if (ratio < 0.8) {
    return head + Format(": %s is lower by %.0f%% (ratio %.2f).", a.options.name.c_str(),
                         100.0 * (1.0 - ratio), ratio);
  }
  if (ratio > 1.25) {
    return head + Format(": %s is lower by %.0f%% (ratio %.2f).", b.options.name.c_str(),
                         100.0 * (1.0 - 1.0 / ratio), ratio);
  }
  return head + Format(": within 20%% of each other (ratio %.2f), this run does not separate them.",
                       ratio);
}

std::string IntegritySentences(const std::vector<RunRecord>& runs) {
  std::string out;
  for (const RunRecord& r : runs) {
    const int n = static_cast<int>(r.frames.size());
    const int graded =
        r.frames_by_integrity[0] + r.frames_by_integrity[1] + r.frames_by_integrity[2];
    if (graded == 0) {
      out +=
          (out.empty() ? "" : " ") + r.options.name + ": the pipeline reports no integrity status.";
      continue;
    }
    std::string s = Format("%s navigation output: %d VALID, %d DEGRADED, %d INVALID of %d frames",
                           r.options.name.c_str(), r.frames_by_integrity[0],
                           r.frames_by_integrity[1], r.frames_by_integrity[2], n);
    if (r.misleading_frames > 0) {
      s += Format(
          "; **%d VALID frames had a position error beyond the protection level (first "
          "at frame %d): wrong without saying so**",
          r.misleading_frames, r.first_misleading_frame);
    } else {
      s += "; no VALID frame had an error beyond its protection level";
    }
    if (r.degraded_beyond_protection > 0) {
      s += Format("; %d DEGRADED frames exceeded theirs", r.degraded_beyond_protection);
    }
    out += (out.empty() ? "" : " ") + s + ".";
  }
  return out;
}

std::string FailureSentences(const std::vector<RunRecord>& runs) {
  std::string out;
  for (const RunRecord& r : runs) {
    if (r.Ok()) continue;
    out += Format("%s%s failed (%s): %s.", out.empty() ? "" : " ", r.options.name.c_str(),
                  ToString(r.verdict), r.reason.c_str());
  }
  return out;
}

}  // namespace swf::eval
