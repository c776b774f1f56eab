#include "sequence.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>

#include "euroc_imu.hpp"
#include "report.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/drivers/process_input.hpp"
#include "swf/ground_cli/ground_cli.hpp"
#include "swf/image_io/image_io.hpp"

namespace swf::eval {
namespace {

using core::Status;

frontend::HarrisOptions DetectorFor(int width, int height) {
  // About one bucket per 40 x 40 px, so the corners spread over the whole image.
  frontend::HarrisOptions o;
  o.bucket_cols = std::max(1, std::min(64, width / 40));
  o.bucket_rows = std::max(1, std::min(64, height / 40));
  return o;
}

// Decoded images of the sequence; a file shown more than once (a looped sequence) is decoded
// once and kept, every other one is decoded when needed.
class ImageStore {
 public:
  explicit ImageStore(const StereoSequence& s) {
    std::map<std::string, int> uses;
    for (const SequenceFrame& f : s.frames) {
      ++uses[f.left_path];
      ++uses[f.right_path];
    }
    for (const auto& [path, n] : uses) {
      if (n > 1) keep_[path] = image_io::GrayImage{};
    }
  }
  // The image at `path`, or nullptr with *error.
  const image_io::GrayImage* Get(const std::string& path, int slot, std::string* error) {
    const auto kept = keep_.find(path);
    image_io::GrayImage* image = kept != keep_.end() ? &kept->second : &scratch_[slot];
    if (kept != keep_.end() && image->width > 0) return image;
    if (!image_io::LoadGray(path, image, error)) return nullptr;
    return image;
  }

 private:
  std::map<std::string, image_io::GrayImage> keep_;
  image_io::GrayImage scratch_[2];
};

// NaN when the output carries no covariance (all zero: the pipeline could not compute one), so
// that a missing covariance never reads as certainty.
double PositionSigma(const app::NavOutput& nav) {
  const double trace = nav.covariance[0] + nav.covariance[7] + nav.covariance[14];
  return trace > 0.0 ? std::sqrt(trace) : std::numeric_limits<double>::quiet_NaN();
}

PoseD PoseOf(const app::NavOutput& nav) {
  PoseD p;
  const Eigen::Quaterniond q(nav.orientation_world_q[0], nav.orientation_world_q[1],
                             nav.orientation_world_q[2], nav.orientation_world_q[3]);
  p.R = q.toRotationMatrix();
  p.t = Vec3D(nav.position_world_m[0], nav.position_world_m[1], nav.position_world_m[2]);
  return p;
}

std::string FrameName(const StereoSequence& s, std::size_t j) {
  const SequenceFrame& f = s.frames[j];
  std::string name = "frame " + std::to_string(j);
  if (f.source != static_cast<int>(j)) name += " (recorded frame " + std::to_string(f.source) + ")";
  return name + " [" + f.record + "]";
}

void Fail(RunRecord* run, Verdict verdict, int frame, const std::string& reason) {
  if (!run->Ok()) return;  // the first failure is the one that explains the rest
  run->verdict = verdict;
  run->failure_frame = frame;
  run->reason = reason;
}

// What the navigation output says about the frame.
void RecordNav(const app::NavOutput& nav, FrameRecord* record) {
  record->estimate = PoseOf(nav);
  record->window_measurements = nav.num_measurements;
  record->iterations = nav.iterations;
  record->fault_bits = static_cast<std::uint32_t>(nav.fault_bits);
  record->position_sigma_m = PositionSigma(nav);
  record->integrity = nav.status;
  record->integrity_flags = static_cast<std::uint32_t>(nav.integrity_flags);
  record->hpl_m = nav.horizontal_protection_m;
  record->vpl_m = nav.vertical_protection_m;
}

// Runs the pipeline stages of frame j; false (with the run's verdict set) when the pipeline
// refuses the input, after which nothing later can be scored.
bool ProcessFrame(const StereoSequence& s, std::size_t j, ImageStore* images,
                  drivers::StoredImuProvider* imu, app::Pipeline* pipeline, RunRecord* run,
                  FrameRecord* record) {
  const SequenceFrame& f = s.frames[j];
  std::string error;
  const image_io::GrayImage* left = images->Get(f.left_path, 0, &error);
  const image_io::GrayImage* right = left ? images->Get(f.right_path, 1, &error) : nullptr;
  if (left == nullptr || right == nullptr) {
    Fail(run, Verdict::kInputError, static_cast<int>(j), FrameName(s, j) + ": " + error);
    return false;
  }
  app::PipelineFrame frame;
  frame.left = left->View();
  frame.right = right->View();
  frame.utime = NsToUs(f.stamp_ns);
  frame.seq = static_cast<std::int64_t>(j);
  // The IMU samples stamped up to this exposure, as the flight loop hands them over.
  estimator::ImuSample<double> sample;
  while (pipeline->Inertial() && imu->NextImu(frame.utime, &sample)) pipeline->AddImu(sample);
  Status st = pipeline->Rectify(frame);
  if (st == Status::kOk) st = pipeline->Track();
  if (st != Status::kOk) {
    Fail(run, Verdict::kInputError, static_cast<int>(j),
         FrameName(s, j) + ": the pipeline refused the images (" + core::ToString(st) + "; " +
             std::to_string(left->width) + "x" + std::to_string(left->height) + " px, expected " +
             std::to_string(s.width) + "x" + std::to_string(s.height) + ")");
    return false;
  }
  record->tracked = pipeline->NumFeatures();
  PoseD truth_step;
  if (run->options.truth_motion && j > 0) truth_step = s.frames[j - 1].truth.Inverse() * f.truth;
  st = pipeline->Estimate(run->options.truth_motion && j > 0 ? &truth_step : nullptr);
  record->status = static_cast<int>(st);
  run->estimate_failures += st != Status::kOk;
  app::NavOutput nav;
  pipeline->MakeNav(&nav);
  RecordNav(nav, record);
  return true;
}

const char* IntegrityName(int status) {
  static const char* const kNames[] = {"VALID", "DEGRADED", "INVALID"};
  return status >= 0 && status <= 2 ? kNames[status] : "UNKNOWN";
}

// The pipeline's integrity at a frame, for a failure's reason: whether it had said so.
std::string IntegrityAt(const FrameRecord& r) {
  if (r.integrity < 0) return "";
  return Format("; the navigation output said %s (flags 0x%x, HPL %.3g m, VPL %.3g m)",
                IntegrityName(r.integrity), r.integrity_flags, r.hpl_m, r.vpl_m);
}

// Counts the frame's integrity status and whether its error exceeded what the output claimed.
void CountIntegrity(std::size_t j, const FrameRecord& r, RunRecord* run) {
  if (r.integrity >= 0 && r.integrity <= 2) ++run->frames_by_integrity[r.integrity];
  const bool beyond = r.horizontal_error_m > r.hpl_m || r.vertical_error_m > r.vpl_m;
  if (r.Misleading()) {
    ++run->misleading_frames;
    if (run->first_misleading_frame < 0) run->first_misleading_frame = static_cast<int>(j);
  } else if (r.integrity == 1 && beyond) {
    ++run->degraded_beyond_protection;
  }
}

// Checks frame j's estimate against the truth and the measurement count; sets the verdict at
// the first frame that is non-finite, diverged or without tracked landmarks.
void Judge(const StereoSequence& s, std::size_t j, const RunOptions& o, RunRecord* run,
           FrameRecord* r) {
  const int frame = static_cast<int>(j);
  if (!IsFinite(r->estimate)) {
    Fail(run, Verdict::kNonFinite, frame, FrameName(s, j) + ": the estimated pose is not finite");
    r->anchored_error_m = std::numeric_limits<double>::quiet_NaN();
    return;
  }
  // The estimate's world is the first camera (the pipeline starts at identity), so the truth
  // moved into its own first camera frame is directly comparable, as the protection levels are.
  const Vec3D truth = (s.frames[0].truth.Inverse() * s.frames[j].truth).t;
  const Vec3D error = r->estimate.t - truth;
  r->anchored_error_m = error.norm();
  r->vertical_error_m = std::fabs(error.dot(s.up_world));
  r->horizontal_error_m = (error - error.dot(s.up_world) * s.up_world).norm();
  if (!(r->anchored_error_m <= o.divergence_m)) {
    Fail(run, Verdict::kDiverged, frame,
         FrameName(s, j) +
             Format(": position error %.3g m from the truth (limit %.3g m), %d tracked landmarks, "
                    "%d measurements in the window, fault bits 0x%x",
                    r->anchored_error_m, o.divergence_m, r->tracked, r->window_measurements,
                    r->fault_bits) +
             IntegrityAt(*r));
  }
  if (j > 0 && r->tracked == 0) {
    ++run->frames_without_tracks;
    Fail(run, Verdict::kNoMeasurements, frame,
         FrameName(s, j) +
             ": no landmark was tracked into this frame, so its pose is the process model's "
             "guess (0 measurements: check the calibration and the images)");
  }
}

// RunOptions::measurements_path: per frame the true pose in the estimate's world (the first
// camera), the front end's features of the left image with their fate, and the filter's
// landmarks (MakeMap: the estimate and its marginal covariance). Read by
// tools/eval/real_frames.py, which triangulates every track with the true poses held.
class MeasurementLog {
 public:
  void Add(const StereoSequence& s, std::size_t j, const PoseD& estimate, app::Pipeline* pipeline) {
    const PoseD truth = s.frames[0].truth.Inverse() * s.frames[j].truth;
    Json frame;
    frame["frame"] = j;
    frame["record"] = s.frames[j].record;
    AddPose(truth, "true", &frame);
    AddPose(estimate, "estimated", &frame);
    Json features = Json::array();  // [id, u, v, fate]: app::FeatureFate
    const app::FeatureMark* marks = pipeline->FeatureMarks();
    for (int k = 0; k < pipeline->NumFeatureMarks(); ++k) {
      features.push_back(
          {marks[k].id, marks[k].u_px, marks[k].v_px, static_cast<int>(marks[k].fate)});
    }
    frame["features"] = features;
    Json landmarks = Json::array();  // [id, x, y, z, xx, xy, xz, yy, yz, zz]
    if (pipeline->MakeMap(map_.get()) == Status::kOk) {
      for (std::int32_t k = 0; k < map_->num_landmarks; ++k) {
        const app::MapLandmark& l = map_->landmarks[k];
        Json row = {l.id};
        const auto number = [](double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); };
        for (double x : l.position_world_m) row.push_back(number(x));
        for (double c : l.covariance_m2) row.push_back(number(c));
        landmarks.push_back(row);
      }
    }
    frame["landmarks"] = landmarks;
    frames_.push_back(frame);
  }

  static void AddPose(const PoseD& pose, const std::string& which, Json* frame) {
    Json r = Json::array();
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) r.push_back(pose.R(row, col));
    (*frame)[which + "_world_R_camera"] = r;
    (*frame)[which + "_world_t_camera_m"] = {pose.t.x(), pose.t.y(), pose.t.z()};
  }

  bool Write(const std::string& path, const StereoSequence& s, const RunOptions& o,
             std::string* error) const {
    Json doc;
    doc["sequence"] = s.dir;
    doc["run"] = o.name;
    doc["camera"] = {{"fx", s.camera.fx},
                     {"fy", s.camera.fy},
                     {"cx", s.camera.cx},
                     {"cy", s.camera.cy},
                     {"baseline_m", s.camera.baseline_m},
                     {"width_px", s.width},
                     {"height_px", s.height}};
    doc["fates"] = {"tracked", "new", "rejected", "gated"};
    doc["frames"] = frames_;
    return ground_cli::WriteJson(path, doc, error, -1);
  }

 private:
  Json frames_ = Json::array();
  std::unique_ptr<app::MapOutput> map_ = std::make_unique<app::MapOutput>();
};

}  // namespace

app::PipelineOptions PipelineFor(const StereoSequence& s, const RunOptions& r) {
  app::PipelineOptions o;
  o.rectify = s.rectify;
  o.left_calibration = s.calibration[0];
  o.right_calibration = s.calibration[1];
  o.camera = s.camera;
  o.width_px = s.width;
  o.height_px = s.height;
  o.frontend.harris = DetectorFor(s.width, s.height);
  o.frontend.max_tracks = r.max_tracks;
  o.frontend.stereo.max_disparity = r.max_disparity_px;
  o.swf.mode = r.mode;
  o.swf.window_size = r.window;
  o.measurement_sigma_px = r.sigma_px;
  o.process_sigma_m = r.process_sigma_m;
  o.process_sigma_rad = r.process_sigma_rad;
  o.integrity.up_world = s.up_world;
  if (r.imu && s.HasImu()) {
    o.imu.enabled = true;
    o.imu.noise = s.imu_noise;
    o.imu.stream.nominal_period_us = s.imu_period_us;
    o.imu.imu_T_camera = s.imu_T_camera;
    o.imu.gravity_world_mps2 = s.gravity_world_mps2;
    o.imu.initial_velocity_world_mps = s.initial_velocity_mps;
    o.imu.first_gyro_bias_sigma_radps = r.gyro_bias_sigma_radps;
    o.imu.first_accel_bias_sigma_mps2 = r.accel_bias_sigma_mps2;
  }
  return o;  // initial_world_T_camera: identity, the estimate's world is the first camera
}

std::vector<RunRecord> RunSwfAndVo(const StereoSequence& sequence, const RunOptions& base) {
  std::vector<RunRecord> runs;
  const std::string k = std::to_string(base.window);
  for (const auto mode :
       {estimator::SwfMode::kSlidingWindow, estimator::SwfMode::kVisualOdometry}) {
    RunOptions o = base;
    o.name = (mode == estimator::SwfMode::kSlidingWindow ? "SWF(" : "VO(") + k + ")";
    o.mode = mode;
    if (mode != estimator::SwfMode::kSlidingWindow) o.measurements_path.clear();  // SWF's only
    runs.push_back(RunSequence(sequence, o));
  }
  if (sequence.HasImu()) {
    RunOptions o = base;
    o.measurements_path.clear();
    o.name = "SWF(" + k + ") + IMU";
    o.imu = true;
    runs.push_back(RunSequence(sequence, o));
  }
  return runs;
}

bool FrameRecord::Misleading() const {
  return integrity == 0 && (horizontal_error_m > hpl_m || vertical_error_m > vpl_m);
}

const char* ToString(Verdict verdict) {
  switch (verdict) {
    case Verdict::kOk: return "ok";
    case Verdict::kInputError: return "input_error";
    case Verdict::kNonFinite: return "non_finite";
    case Verdict::kDiverged: return "diverged";
    case Verdict::kNoMeasurements: return "no_measurements";
  }
  return "unknown";
}

RunRecord RunSequence(const StereoSequence& sequence, const RunOptions& options) {
  RunRecord run;
  run.options = options;
  auto pipeline = std::make_unique<app::Pipeline>();
  const Status st = pipeline->Configure(PipelineFor(sequence, options));
  if (st != Status::kOk) {
    Fail(&run, Verdict::kInputError, -1,
         sequence.dir + ": the flight pipeline refused the configuration (" + core::ToString(st) +
             ")");
    return run;
  }
  ImageStore images(sequence);
  const auto start = std::chrono::steady_clock::now();
  double tracked = 0.0;
  drivers::StoredImuProvider imu;
  imu.Reset(&sequence.imu);
  std::unique_ptr<MeasurementLog> log;
  if (!options.measurements_path.empty()) log = std::make_unique<MeasurementLog>();
  for (std::size_t j = 0; j < sequence.frames.size(); ++j) {
    FrameRecord record;
    if (!ProcessFrame(sequence, j, &images, &imu, pipeline.get(), &run, &record)) break;
    if (log) log->Add(sequence, j, record.estimate, pipeline.get());
    Judge(sequence, j, options, &run, &record);
    CountIntegrity(j, record, &run);
    tracked += record.tracked;
    run.frames.push_back(record);
    if (run.verdict == Verdict::kNonFinite) break;  // nothing later can be scored
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::string error;
  if (log && !log->Write(options.measurements_path, sequence, options, &error))
    Fail(&run, Verdict::kInputError, -1, "--measurements: " + error);
  if (const estimator::NavState<double>* x = pipeline->NewestNavState()) {
    run.has_biases = true;
    run.gyro_bias_radps = x->biases.gyro_radps;
    run.accel_bias_mps2 = x->biases.accel_mps2;
  }
  if (pipeline->Inertial()) {
    const app::ImuCounts c = pipeline->ImuStreamCounts();
    run.imu_samples_accepted = c.stream.accepted;
    run.imu_samples_dropped = c.stream.out_of_order + c.stream.duplicated + c.stream.invalid +
                              c.stream.saturated + c.overflowed;
    run.imu_intervals_bridged = c.intervals_bridged;
  }
  if (run.frames.empty()) return run;
  run.mean_tracked = tracked / static_cast<double>(run.frames.size());
  std::vector<PoseD> truth;
  std::vector<PoseD> estimate;
  for (std::size_t j = 0; j < run.frames.size(); ++j) {
    truth.push_back(sequence.frames[j].truth);
    estimate.push_back(run.frames[j].estimate);
  }
  run.errors = ScoreTrajectory(truth, estimate);
  return run;
}

std::vector<RunRecord> DiagnoseFailures(const StereoSequence& sequence,
                                        const std::vector<RunRecord>& runs) {
  std::vector<RunRecord> out;
  for (const RunRecord& r : runs) {
    if (r.verdict != Verdict::kDiverged && r.verdict != Verdict::kNonFinite) continue;
    RunOptions o = r.options;
    o.truth_motion = true;
    o.measurements_path.clear();
    o.name += " with the true motion as input";
    out.push_back(RunSequence(sequence, o));
  }
  return out;
}

std::vector<int> PingPong(int n, int total) {
  std::vector<int> out;
  if (n <= 0) return out;
  const int period = n > 1 ? 2 * (n - 1) : 1;
  for (int k = 0; k < total; ++k) {
    const int p = k % period;
    out.push_back(p < n ? p : period - p);
  }
  return out;
}

}  // namespace swf::eval
