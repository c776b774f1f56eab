#include "commands.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "euroc.hpp"
#include "experiment_file.hpp"
#include "json.hpp"
#include "kitti.hpp"
#include "report.hpp"
#include "swf/cli/cli.hpp"
#include "swf/evaluation/statistics.hpp"
#include "swf/frontend/config.hpp"
#include "swf/ground_cli/ground_cli.hpp"

namespace swf::eval {
namespace {

using evaluation::Median;

// What one command hands to the common writer.
struct Evaluation {
  std::string prefix;   // file names: OUT/<prefix>.json, .md, _error.dat, _swf_tum.txt, ...
  std::string title;    // markdown heading
  std::string dataset;  // plain, for the figure's title: "EuRoC V1_01", ...
  const StereoSequence* sequence = nullptr;
  const std::vector<RunRecord>* runs = nullptr;
  const std::vector<RunRecord>* diagnostics = nullptr;  // re-runs of failed runs, may be empty
  Json header;                                          // dataset fields, first in the JSON
  Json run;                 // swf::ground_cli::RunEcho of the command line, last in every JSON
  std::string description;  // markdown before the table
  std::string notes;        // markdown after the comparison, computed by the command
};

// A real-data evaluation's results and the header fields that name it (experiment, build,
// dataset directory), the same for every sequence command.
template <typename SequenceResult>
Evaluation EvaluationOf(const std::string& prefix, const SequenceArgs& args,
                        const SequenceResult& result) {
  Evaluation e;
  e.prefix = prefix;
  e.sequence = &result.sequence;
  e.runs = &result.runs;
  e.diagnostics = &result.diagnostics;
  e.header = {{"experiment", prefix},
              {"version", cli::Version()},
              {"commit", cli::Commit()},
              {"dataset", args.dir}};
  e.run = args.run;
  return e;
}

std::string Key(const RunRecord& r) {
  if (r.options.imu) return "swf_imu";
  return r.options.mode == estimator::SwfMode::kSlidingWindow ? "swf" : "vo";
}

// Every file a command with this prefix can write into OUT (each Key() a run can have): what
// --measurements must not name, or the report would overwrite it after the run.
std::vector<std::string> ReportFiles(const std::string& prefix) {
  std::vector<std::string> names = {prefix + ".json", prefix + ".md", prefix + "_error.dat",
                                    prefix + "_error.json"};
  for (const char* key : {"swf", "vo", "swf_imu"}) {
    names.push_back(prefix + "_" + key + "_tum.txt");
    names.push_back(prefix + "_" + key + "_frames.tsv");
  }
  return names;
}

// False, after saying why, when --measurements names one of the report's own files (compared
// as absolute paths with `.`, `..` and existing symbolic links resolved).
bool MeasurementsApartFromReport(const char* tool, const SequenceArgs& a,
                                 const std::string& prefix) {
  if (a.measurements.empty()) return true;
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path measurements = fs::weakly_canonical(fs::absolute(a.measurements, ec), ec);
  for (const std::string& name : ReportFiles(prefix)) {
    const fs::path report = fs::weakly_canonical(fs::absolute(fs::path(a.out) / name, ec), ec);
    if (!ec && report == measurements) {
      std::fprintf(stderr,
                   "%s: --measurements %s is the run's own report file %s/%s, which the run "
                   "writes after the measurements: name another file\n",
                   tool, a.measurements.c_str(), a.out.c_str(), name.c_str());
      return false;
    }
  }
  return true;
}

// Every frame of a run, to see where and how a run went wrong.
bool WriteFrameTable(const std::string& path, const RunRecord& r, const StereoSequence& s,
                     std::string* error) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    *error = path + ": cannot write";
    return false;
  }
  std::fprintf(f,
               "# frame\trecorded\tt_s\terror_no_fit_m\tsigma_m\ttracked\twindow_meas\t"
               "iterations\tfault_bits\tstatus\test_x\test_y\test_z\ttrue_x\ttrue_y\ttrue_z\t"
               "integrity\tintegrity_flags\thpl_m\tvpl_m\terror_h_m\terror_v_m\n");
  for (std::size_t j = 0; j < r.frames.size(); ++j) {
    const FrameRecord& fr = r.frames[j];
    const Vec3D truth = (s.frames[0].truth.Inverse() * s.frames[j].truth).t;
    const Vec3D est = fr.estimate.t;  // the estimate's world is the first camera
    std::fprintf(f, "%zu\t%d\t%.3f\t%.6g\t%.6g\t%d\t%d\t%d\t0x%x\t%d\t", j, s.frames[j].source,
                 1e-9 * static_cast<double>(s.frames[j].stamp_ns - s.frames[0].stamp_ns),
                 fr.anchored_error_m, fr.position_sigma_m, fr.tracked, fr.window_measurements,
                 fr.iterations, fr.fault_bits, fr.status);
    std::fprintf(f, "%.6g\t%.6g\t%.6g\t%.6g\t%.6g\t%.6g\t%d\t0x%x\t%.6g\t%.6g\t%.6g\t%.6g\n",
                 est.x(), est.y(), est.z(), truth.x(), truth.y(), truth.z(), fr.integrity,
                 fr.integrity_flags, fr.hpl_m, fr.vpl_m, fr.horizontal_error_m,
                 fr.vertical_error_m);
  }
  if (std::fclose(f) != 0) {
    *error = path + ": cannot write";
    return false;
  }
  return true;
}

bool WriteTrajectories(const std::string& out, const Evaluation& e, std::string* error) {
  for (const RunRecord& r : *e.runs) {
    std::vector<TumPose> poses;
    for (std::size_t j = 0; j < r.frames.size(); ++j) {
      poses.push_back(
          {1e-9 * static_cast<double>(e.sequence->frames[j].stamp_ns), r.frames[j].estimate});
    }
    const std::string path = out + "/" + e.prefix + "_" + Key(r) + "_tum.txt";
    if (!WriteTum(path, poses)) {
      *error = path + ": cannot write";
      return false;
    }
    if (!WriteFrameTable(out + "/" + e.prefix + "_" + Key(r) + "_frames.tsv", r, *e.sequence,
                         error)) {
      return false;
    }
  }
  return true;
}

Json JsonOf(const Evaluation& e) {
  Json o = e.header;
  Json ate = Json::object();
  for (const RunRecord& r : *e.runs) {
    if (r.Ok()) {
      SetNumber(&ate, Key(r), r.errors.ate_rmse_m, r.errors.reason);
    } else {
      SetNull(&ate, Key(r), "no score: " + std::string(ToString(r.verdict)) + ", " + r.reason);
    }
  }
  o["ate_rmse_m"] = ate;
  o["all_runs_ok"] = AllOk(*e.runs);
  for (const RunRecord& r : *e.runs) {
    o[Key(r)] = RunJson(r, *e.sequence, e.prefix + "_" + Key(r) + "_tum.txt");
  }
  Json diagnosis = Json::object();
  for (const RunRecord& r : *e.diagnostics) {
    diagnosis[Key(r) + "_true_motion"] = RunJson(r, *e.sequence, "");
  }
  o["diagnostics"] = diagnosis;
  o["run"] = e.run;
  return o;
}

bool WriteErrorSeries(const std::string& out, const Evaluation& e) {
  std::vector<Series> series;
  const std::size_t n = e.sequence->frames.size();
  for (const RunRecord& r : *e.runs) {
    Series aligned{r.options.name + " position error after SE(3) fit (m)",
                   std::vector<double>(n, NAN)};
    Series anchored{r.options.name + " position error, no fit (m)", std::vector<double>(n, NAN)};
    for (std::size_t j = 0; j < r.frames.size(); ++j) {
      anchored.y[j] = r.frames[j].anchored_error_m;
      if (j < r.errors.aligned_error_m.size()) aligned.y[j] = r.errors.aligned_error_m[j];
    }
    series.push_back(aligned);
    series.push_back(anchored);
  }
  // The diagnosis re-runs beside them: what the same images give with a motion input.
  for (const RunRecord& r : *e.diagnostics) {
    Series anchored{r.options.name + ", error no fit (m)", std::vector<double>(n, NAN)};
    for (std::size_t j = 0; j < r.frames.size(); ++j) anchored.y[j] = r.frames[j].anchored_error_m;
    series.push_back(anchored);
  }
  const Figure figure{e.dataset + ": position error of each run, frame by frame", "frame number",
                      "position error (m)", false};
  return WriteExperiment({out, e.run}, e.prefix + "_error", figure, series,
                         {{"dataset", e.sequence->dir}});
}

// What the re-runs with the true motion say about the failed runs.
std::string DiagnosisSentences(const std::vector<RunRecord>& diagnostics) {
  std::string out;
  for (const RunRecord& r : diagnostics) {
    if (!out.empty()) out += " ";
    if (r.Ok()) {
      out += Format(
          "Diagnosis: %s stays within the divergence limit over all %zu frames (largest error "
          "without fit %.3g m, last frame %.3g m, ATE %.3g m): the images and the front end can "
          "carry this trajectory, what fails is the estimate without a motion input.",
          r.options.name.c_str(), r.frames.size(), r.errors.max_anchored_error_m,
          r.errors.final_anchored_error_m, r.errors.ate_rmse_m);
    } else {
      out += Format("Diagnosis: %s fails too (%s): %s.", r.options.name.c_str(),
                    ToString(r.verdict), r.reason.c_str());
    }
  }
  return out;
}

std::string Markdown(const Evaluation& e) {
  const std::vector<RunRecord>& runs = *e.runs;
  std::string md = "## " + e.title + "\n\n![" + e.prefix + "](eval/" + e.prefix +
                   "_error.png)\n\n" + e.description + "\n\n" + RunsTable(runs) + "\n";
  const std::string failures = FailureSentences(runs);
  if (!failures.empty()) md += "**Not every run is scored.** " + failures + "\n\n";
  // SWF against VO; the stereo-inertial run (when the dataset has an IMU) against SWF.
  if (runs.size() >= 2) {
    md += CompareSentence(runs[0], runs[0].errors.ate_rmse_m, runs[1], runs[1].errors.ate_rmse_m,
                          "ATE");
    if (runs.size() == 3) {
      md += " " + CompareSentence(runs[2], runs[2].errors.ate_rmse_m, runs[0],
                                  runs[0].errors.ate_rmse_m, "ATE");
    }
    md += "\n\n";
  }
  md +=
      "Integrity (error without fit, split along the vertical, against the navigation "
      "output's horizontal and vertical protection levels): " +
      IntegritySentences(runs) + "\n\n";
  if (!e.notes.empty()) md += e.notes + "\n\n";
  const std::string diagnosis = DiagnosisSentences(*e.diagnostics);
  if (!diagnosis.empty()) md += diagnosis + "\n\n";
  return md;
}

// More tracks than the flight prior holds (kMaxPriorLandmarks) drop a marginalized pose's
// sightings of the tracks that did not fit (kFaultPriorCapacity): a run that lost data says so.
std::string PriorOverflowNote(const RunRecord& r) {
  const auto full = std::count_if(r.frames.begin(), r.frames.end(), [](const FrameRecord& f) {
    return (f.fault_bits & estimator::kFaultPriorCapacity) != 0;
  });
  if (full == 0) return "";
  return "; the prior was full at " + std::to_string(full) + " of " +
         std::to_string(r.frames.size()) + " frames: sightings dropped (kFaultPriorCapacity)";
}

// Writes every file of the evaluation and returns the exit status.
int WriteEvaluation(const std::string& out, const Evaluation& e) {
  std::string error;
  if (!WriteTrajectories(out, e, &error) ||
      !ground_cli::WriteJson(out + "/" + e.prefix + ".json", JsonOf(e), &error)) {
    std::fprintf(stderr, "swf-eval: %s\n", error.c_str());
    return 1;
  }
  std::printf("swf-eval: wrote %s/%s.json\n", out.c_str(), e.prefix.c_str());
  if (!WriteErrorSeries(out, e)) return 1;
  std::ofstream md(out + "/" + e.prefix + ".md");
  md << Markdown(e);
  md.close();
  if (!md) {
    std::fprintf(stderr, "swf-eval: %s/%s.md: cannot write\n", out.c_str(), e.prefix.c_str());
    return 1;
  }
  std::printf("swf-eval: wrote %s/%s.md\n", out.c_str(), e.prefix.c_str());
  for (const RunRecord& r : *e.runs) {
    if (r.Ok()) {
      std::printf(
          "swf-eval: %s ok: ATE %.4g m, last frame %.4g m without fit, %.0f tracked/frame%s\n",
          r.options.name.c_str(), r.errors.ate_rmse_m, r.errors.final_anchored_error_m,
          r.mean_tracked, PriorOverflowNote(r).c_str());
    } else {
      std::fprintf(stderr, "swf-eval: %s %s: %s\n", r.options.name.c_str(), ToString(r.verdict),
                   r.reason.c_str());
    }
  }
  return AllOk(*e.runs) ? 0 : kExitRunFailed;
}

// What every sequence command does before its report: --measurements checked against the
// report's own files, the output directory created and the dataset run. 0, or the exit status
// (kExitBadArguments, 1) after saying what failed.
template <typename Run>
int CheckAndRun(const char* tool, const SequenceArgs& a, const std::string& prefix,
                const Run& run) {
  if (!MeasurementsApartFromReport(tool, a, prefix)) return kExitBadArguments;
  std::string error;
  if (!cli::MakeDirectories(a.out, &error) || !run(&error)) {
    std::fprintf(stderr, "%s: %s\n", tool, error.c_str());
    return 1;
  }
  return 0;
}

// The flags every dataset command shares, onto its runs' options.
void ApplyCommon(const SequenceArgs& a, RunOptions* run) {
  run->window = a.window;
  if (a.max_tracks > 0) run->max_tracks = static_cast<std::size_t>(a.max_tracks);
  if (a.motion_sigma_m > 0.0) {
    run->process_sigma_m = a.motion_sigma_m;
    run->process_sigma_rad = a.motion_sigma_rad;
  }
  if (a.divergence_m > 0.0) run->divergence_m = a.divergence_m;
  run->measurements_path = a.measurements;
}

// Shared paragraph: what ran.
std::string PipelineSentence(const StereoSequence& s, const RunOptions& o) {
  return Format(
      "The flight pipeline (`swf::app::Pipeline`: %s, front end with at most %zu tracks and a "
      "%d px disparity search, Sliding Window Filter window %d) with no motion input: the "
      "constant-velocity process model carries the pose between frames (process noise %.3g m "
      "and %.3g rad per frame). Stereo rig: f = %.1f px, baseline %.4f m, %d x %d px.",
      s.rectify ? "rectification from the calibration files" : "images already rectified",
      o.max_tracks, o.max_disparity_px, o.window, o.process_sigma_m, o.process_sigma_rad,
      s.camera.fx, s.camera.baseline_m, s.width, s.height);
}

// A length for the text: "0.0123 m", or why there is no number.
std::string Meters(double value) {
  if (std::isfinite(value)) return Format("%.4g m", value);
  return std::isnan(value) ? "not a number" : "not finite (overflow)";
}

// Where a run's error without fit was largest (or first stopped being a finite number).
std::string LargestError(const RunRecord& run) {
  const std::vector<FrameRecord>& f = run.frames;
  if (f.empty()) return run.options.name + ": no frame processed.";
  std::size_t worst = 0;
  for (std::size_t j = 0; j < f.size(); ++j) {
    if (!std::isfinite(f[j].anchored_error_m)) {
      return Format("%s: the error without fit stops being a finite number at frame %zu.",
                    run.options.name.c_str(), j);
    }
    if (f[j].anchored_error_m > f[worst].anchored_error_m) worst = j;
  }
  return Format("%s: largest error without fit %s at frame %zu, last frame %s.",
                run.options.name.c_str(), Meters(f[worst].anchored_error_m).c_str(), worst,
                Meters(f.back().anchored_error_m).c_str());
}

std::string CheckpointTable(const std::vector<RunRecord>& runs, const StereoSequence& s) {
  std::string t = "| t (s) | frame |";
  std::string rule = "|---|---|";
  for (const RunRecord& r : runs) {
    t += " " + r.options.name + " error, no fit | " + r.options.name + " 1-sigma |";
    rule += "---|---|";
  }
  t += "\n" + rule + "\n";
  const std::size_t n = s.frames.size();
  for (int k = 1; k <= 6; ++k) {
    const std::size_t j = std::min(n - 1, k * n / 6);
    t += Format("| %.1f | %zu |",
                1e-9 * static_cast<double>(s.frames[j].stamp_ns - s.frames[0].stamp_ns), j);
    for (const RunRecord& r : runs) {
      if (j < r.frames.size()) {
        const double sigma = r.frames[j].position_sigma_m;
        const std::string error = Meters(r.frames[j].anchored_error_m);
        const std::string claimed = std::isnan(sigma) ? "no covariance" : Meters(sigma);
        t += Format(" %s | %s |", error.c_str(), claimed.c_str());
      } else {
        t += " - | - |";
      }
    }
    t += "\n";
  }
  return t;
}

// How far the error of a scored run grows over the run, from the numbers.
std::string GrowthSentence(const RunRecord& r) {
  if (!r.Ok()) return "";
  const double median = Median(r.errors.aligned_error_m);
  const double last = r.errors.final_aligned_error_m;
  std::string s = Format("%s: median position error after the fit %.2f mm, last frame %.2f mm",
                         r.options.name.c_str(), 1e3 * median, 1e3 * last);
  if (last > 3.0 * median)
    s +=
        Format(" (%.1fx the median: the error grows over the run)", last / std::max(median, 1e-12));
  return s + ".";
}

// What the stereo-inertial run used and what it estimated of the IMU.
std::string ImuSentence(const RunRecord& run, const StereoSequence& s) {
  const estimator::ImuNoise<double>& n = s.imu_noise;
  return Format(
      "%s: the stereo-inertial estimator, in place of the constant-velocity model: the recorded "
      "IMU (`imu0`, %lld samples used, %lld dropped by the stream checks, %lld frame intervals "
      "bridged over a gap) preintegrated between exposures with the noise of `sensor.yaml` "
      "(gyroscope %.4g rad/s/sqrt(Hz), random walk %.4g rad/s^2/sqrt(Hz); accelerometer %.4g "
      "m/s^2/sqrt(Hz), random walk %.4g m/s^3/sqrt(Hz)); start: gravity's direction and the "
      "IMU's velocity from the ground truth (what the state guidance would hand over), biases "
      "zero with prior sigmas %.3g rad/s and %.3g m/s^2 (no static calibration before the first "
      "frame). Biases estimated at the last frame: gyroscope (%.4f, %.4f, %.4f) rad/s, "
      "accelerometer (%.3f, %.3f, %.3f) m/s^2.",
      run.options.name.c_str(), static_cast<long long>(run.imu_samples_accepted),
      static_cast<long long>(run.imu_samples_dropped),
      static_cast<long long>(run.imu_intervals_bridged), n.gyro_noise_density, n.gyro_random_walk,
      n.accel_noise_density, n.accel_random_walk, run.options.gyro_bias_sigma_radps,
      run.options.accel_bias_sigma_mps2, run.gyro_bias_radps.x(), run.gyro_bias_radps.y(),
      run.gyro_bias_radps.z(), run.accel_bias_mps2.x(), run.accel_bias_mps2.y(),
      run.accel_bias_mps2.z());
}

std::string EurocNotes(const EurocOptions& o, const EurocResult& r) {
  std::string notes = Format(
      "The ground truth's path over the %d recorded frames is %.3f m long and never more than "
      "%.3f m from its start%s",
      r.recorded_frames, r.gt_path_length_m, r.gt_extent_m,
      r.gt_extent_m < 0.05 ? ": the camera is at rest, so the ATE measures drift and jitter at "
                             "rest, not tracking over distance."
                           : ".");
  for (const RunRecord& run : r.runs) {
    const std::string g = GrowthSentence(run);
    if (!g.empty()) notes += " " + g;
  }
  if (o.loop_seconds > 0.0) {
    notes += Format(
        "\n\nLooped: the %d recorded frames played forwards and backwards (ping-pong) into %zu "
        "frames, %.1f s at the recorded %.0f Hz, timestamps monotonic; the truth repeats with "
        "the images. Error without fit (estimate and truth from their first frame) and the "
        "navigation output's own position 1-sigma along the run:\n\n",
        r.recorded_frames, r.sequence.frames.size(), o.loop_seconds, 1.0 / r.frame_interval_s);
    notes += CheckpointTable(r.runs, r.sequence);
    for (const RunRecord& run : r.runs) {
      notes += '\n';
      notes += LargestError(run);
    }
  }
  for (const RunRecord& run : r.runs) {
    if (run.has_biases) notes += "\n\n" + ImuSentence(run, r.sequence);
  }
  if (r.runs.size() == 3 && AllOk(r.runs)) {
    notes += " " + CompareSentence(r.runs[2], r.runs[2].errors.step_translation_mean_m, r.runs[0],
                                   r.runs[0].errors.step_translation_mean_m,
                                   "mean per-frame translation error");
  }
  if (r.skipped_frames > 0) {
    notes += Format("\n\n%d listed frames had no ground truth within 5 ms and were left out.",
                    r.skipped_frames);
  }
  return notes;
}

std::string KittiNotes(const KittiResult& r) {
  const std::size_t n = r.sequence.frames.size();
  std::string notes =
      Format("The truth drives %.1f m in %zu frames (%.2f m per frame).", r.gt_path_length_m, n,
             r.gt_path_length_m / static_cast<double>(std::max<std::size_t>(n - 1, 1)));
  for (const RunRecord& run : r.runs) {
    if (!run.Ok()) continue;
    const TrajectoryErrors& e = run.errors;
    notes += Format(
        " %s ends %.2f m from the true final position without fit (%.1f%% of the path; "
        "largest %.2f m); per-frame relative error %.2f%% of the distance driven and %.4f deg/m.",
        run.options.name.c_str(), e.final_anchored_error_m,
        100.0 * e.final_anchored_error_m / r.gt_path_length_m, e.max_anchored_error_m,
        e.step_translation_percent, e.step_rotation_deg_per_m);
  }
  if (r.runs.size() == 2 && AllOk(r.runs)) {  // the ATE sentence already says why not
    notes += "\n\n" +
             CompareSentence(r.runs[0], r.runs[0].errors.final_anchored_error_m, r.runs[1],
                             r.runs[1].errors.final_anchored_error_m, "final position error") +
             " " +
             CompareSentence(r.runs[0], r.runs[0].errors.step_translation_mean_m, r.runs[1],
                             r.runs[1].errors.step_translation_mean_m,
                             "mean per-frame translation error");
  }
  return notes;
}

}  // namespace

int RunEurocCommand(const SequenceArgs& a, double loop_seconds) {
  const std::string& dir = a.dir;
  EurocOptions options;
  options.loop_seconds = loop_seconds;
  ApplyCommon(a, &options.run);
  const bool looped = options.loop_seconds > 0.0;
  const std::string prefix = looped ? "euroc_loop" : "euroc";
  EurocResult result;
  if (const int failed = CheckAndRun("swf-eval euroc", a, prefix, [&](std::string* error) {
        return RunEuroc(dir, options, &result, error);
      })) {
    return failed;
  }
  Evaluation e = EvaluationOf(prefix, a, result);
  e.title = looped ? Format(
                         "Real data: EuRoC looped, %.0f s at rest (`swf-eval euroc DIR "
                         "--loop-seconds %g`)",
                         options.loop_seconds, options.loop_seconds)
                   : "Real data: EuRoC (`swf-eval euroc DIR`)";
  e.dataset = looped ? Format("EuRoC V1_01 looped, %.0f s at rest", options.loop_seconds)
                     : std::string("EuRoC V1_01");
  Json& h = e.header;
  h["recorded_frames"] = result.recorded_frames;
  h["frames"] = result.sequence.frames.size();
  SetNumber(&h, "loop_seconds", options.loop_seconds);
  h["skipped_frames_without_truth"] = result.skipped_frames;
  h["window"] = options.run.window;
  h["max_tracks"] = options.run.max_tracks;
  SetNumber(&h, "rectified_focal_px", result.sequence.camera.fx);
  SetNumber(&h, "baseline_m", result.sequence.camera.baseline_m);
  SetNumber(&h, "gt_path_length_m", result.gt_path_length_m);
  SetNumber(&h, "gt_extent_m", result.gt_extent_m);
  SetNumber(&h, "divergence_limit_m", options.run.divergence_m);
  h["alignment"] = "SE(3), Horn/Umeyama without scale, all frames; camera positions";
  e.description =
      Format("On `%s` (%d recorded stereo frames%s). ", dir.c_str(), result.recorded_frames,
             looped ? Format(", looped into %zu", result.sequence.frames.size()).c_str() : "") +
      PipelineSentence(result.sequence, result.runs.front().options) +
      Format(
          " The online estimate (newest pose after each frame, rectified left camera) is "
          "written in TUM format (`%s_swf_tum.txt`, `%s_vo_tum.txt`) and compared with "
          "`groundtruth_tum.txt` moved to the same camera; a run whose error without fit "
          "exceeds %.3g m is called diverged and not scored.",
          e.prefix.c_str(), e.prefix.c_str(), options.run.divergence_m);
  e.notes = EurocNotes(options, result);
  return WriteEvaluation(a.out, e);
}

int RunKittiCommand(const SequenceArgs& a, int max_disparity_px, int max_frames) {
  const std::string& dir = a.dir;
  KittiOptions options;
  options.run.max_disparity_px = max_disparity_px;
  options.max_frames = max_frames;
  ApplyCommon(a, &options.run);
  const std::string prefix = "kitti_odometry";
  KittiResult result;
  if (const int failed = CheckAndRun("swf-eval kitti", a, prefix, [&](std::string* error) {
        return RunKitti(dir, options, &result, error);
      })) {
    return failed;
  }
  Evaluation e = EvaluationOf(prefix, a, result);
  e.title = "Real data: KITTI odometry excerpt, the whole pipeline (`swf-eval kitti DIR`)";
  e.dataset = "KITTI odometry excerpt";
  Json& h = e.header;
  h["frames"] = result.sequence.frames.size();
  h["window"] = options.run.window;
  h["max_tracks"] = options.run.max_tracks;
  h["max_disparity_px"] = options.run.max_disparity_px;
  SetNumber(&h, "focal_px", result.sequence.camera.fx);
  SetNumber(&h, "baseline_m", result.sequence.camera.baseline_m);
  SetNumber(&h, "gt_path_length_m", result.gt_path_length_m);
  SetNumber(&h, "divergence_limit_m", options.run.divergence_m);
  h["alignment"] = "SE(3), Horn/Umeyama without scale, all frames; left camera positions";
  h["relative_error"] = "per frame-to-frame motion: truth_step^-1 * estimate_step";
  e.description =
      Format("On `%s` (%zu rectified stereo pairs, 10 Hz). ", dir.c_str(),
             result.sequence.frames.size()) +
      PipelineSentence(result.sequence, result.runs.front().options) +
      Format(
          " The estimate's world is the first left camera, as is `poses.txt`'s, so the "
          "error without fit is the plain difference; a run whose error without fit exceeds "
          "%.3g m is called diverged and not scored. Relative error, KITTI-style per frame: "
          "translation and rotation of truth_step^-1 * estimate_step.",
          options.run.divergence_m);
  e.notes = KittiNotes(result);
  return WriteEvaluation(a.out, e);
}

}  // namespace swf::eval
