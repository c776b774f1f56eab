// Exactness of the Sliding Window Filter on a linear-Gaussian problem, where marginalization
// loses nothing: SWF(K) must equal an independent dense batch solution (estimates and marginal
// covariances) for every K and every order of marginalizations, and SWF(K=1) must equal a
// Kalman filter written independently here; both for 6-dof pose states and for 15-dimensional
// states (pose, velocity, IMU biases) of which the measurements see only the pose.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <memory>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "swf/estimator/sliding_window_filter.hpp"

namespace swf::estimator {
namespace {

// z = A_l l + A_p p_1:6  (3),   p_j+1 = F p_j + u  (D). Additive updates: the model is exactly
// linear. D = 6 is a pose; D = 15 stands for a pose with velocity and IMU biases: the
// measurement sees the first six coordinates only, and F couples all of them.
template <int D>
struct LinearModel {
  using Scalar = double;
  using PoseType = Eigen::Matrix<double, D, 1>;
  using MotionType = PoseType;
  using StateMat = Eigen::Matrix<double, D, D>;
  static constexpr int kStateDim = D;
  Mat36<double> a_pose;
  Mat3<double> a_landmark;
  StateMat f;
  double extra_sigma = 0.3;  // prior sigma of the first state's coordinates beyond the pose

  bool Predict(const PoseType& p, const Vec3<double>& l, Vec3<double>* z, Mat36<double>* j_pose,
               Mat3<double>* j_landmark) const {
    *z = a_landmark * l + a_pose * p.template head<6>();
    if (j_pose != nullptr) {
      *j_pose = a_pose;
      *j_landmark = a_landmark;
    }
    return true;
  }
  bool InitLandmark(const PoseType& p, const Vec3<double>& z, Vec3<double>* l) const {
    *l = a_landmark.inverse() * (z - a_pose * p.template head<6>());
    return true;
  }
  // The filter's anchored landmark surface; a linear landmark needs no anchor.
  struct LandmarkAnchor {};
  bool InitLandmark(const PoseType& p, const Vec3<double>& z, LandmarkAnchor* /*anchor*/,
                    Vec3<double>* l) const {
    return InitLandmark(p, z, l);
  }
  bool Predict(const PoseType& p, const LandmarkAnchor& /*anchor*/, const Vec3<double>& l,
               Vec3<double>* z, Mat36<double>* j_pose, Mat3<double>* j_landmark) const {
    return Predict(p, l, z, j_pose, j_landmark);
  }
  static bool LandmarkPosition(const LandmarkAnchor& /*anchor*/, const Vec3<double>& l,
                               Vec3<double>* position, Mat3<double>* jacobian) {
    *position = l;
    if (jacobian != nullptr) jacobian->setIdentity();
    return true;
  }
  Eigen::Matrix<double, D - 6, 1> FirstStateSigmas() const {
    return Eigen::Matrix<double, D - 6, 1>::Constant(extra_sigma);
  }
  PoseType Propagate(const PoseType& p, const MotionType& u) const { return f * p + u; }
  MotionType RelativeMotion(const PoseType& a, const PoseType& b) const { return b - f * a; }
  PoseType ProcessResidual(const PoseType& prev, const PoseType& next, const MotionType& u,
                           StateMat* j_prev, StateMat* j_next) const {
    *j_prev = -f;
    *j_next = StateMat::Identity();
    return next - (f * prev + u);
  }
  static PoseType Retract(const PoseType& p, const PoseType& d) { return p + d; }
  static PoseType Difference(const PoseType& base, const PoseType& p, StateMat* j) {
    j->setIdentity();
    return p - base;
  }
};

struct Obs {
  int frame;
  int landmark;
  Vec3<double> z;
};

template <int D>
struct Problem {
  using State = Eigen::Matrix<double, D, 1>;
  LinearModel<D> model;
  int frames = 0;
  int landmarks = 0;
  std::vector<State> u;  // u[j] drives frame j (j >= 1)
  std::vector<Obs> obs;  // sorted by frame
  State first_pose;
  double sigma_z = 0.5;
  double sigma_q = 0.05;
  SwfOptions options;
  // Covariances after every frame, as the flight pipeline computes them: they arm the
  // prediction gate (without them a new measurement cannot be tested and is fused).
  bool covariances_each_frame = false;

  // Information of the first state's prior, as the filter builds it (options and model).
  Eigen::Matrix<double, D, 1> FirstStateInformation() const {
    Eigen::Matrix<double, D, 1> pi =
        Eigen::Matrix<double, D, 1>::Constant(1 / (model.extra_sigma * model.extra_sigma));
    pi.template head<3>().setConstant(1 /
                                      (options.first_pose_sigma_m * options.first_pose_sigma_m));
    pi.template segment<3>(3).setConstant(
        1 / (options.first_pose_sigma_rad * options.first_pose_sigma_rad));
    return pi;
  }
};

template <int D>
Problem<D> MakeProblem(std::uint64_t seed, int frames, int landmarks, int min_track,
                       int max_track) {
  using State = Eigen::Matrix<double, D, 1>;
  using StateMat = Eigen::Matrix<double, D, D>;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_int_distribution<int> start(0, frames - 1);
  std::uniform_int_distribution<int> length(min_track, max_track);
  Problem<D> pr;
  pr.frames = frames;
  pr.landmarks = landmarks;
  pr.model.a_landmark = Mat3<double>::Identity() + 0.2 * Mat3<double>::Random();
  pr.model.a_pose.template leftCols<3>() = -Mat3<double>::Identity();
  pr.model.a_pose.template rightCols<3>() = Mat3<double>::Random();
  pr.model.f = StateMat::Identity() + 0.05 * StateMat::Random();
  std::vector<State> truth(frames);
  truth[0] = State::Random();
  pr.u.assign(frames, State::Zero());
  for (int j = 1; j < frames; ++j) {
    pr.u[j] = 0.3 * State::Random();
    State w;
    for (int k = 0; k < D; ++k) w[k] = pr.sigma_q * g(rng);
    truth[j] = pr.model.f * truth[j - 1] + pr.u[j] + w;
  }
  std::vector<Vec3<double>> points(landmarks);
  std::vector<std::pair<int, int>> tracks(landmarks);
  for (int i = 0; i < landmarks; ++i) {
    points[i] = 5.0 * Vec3<double>::Random();
    const int s = start(rng);
    tracks[i] = {s, std::min(frames, s + length(rng))};
  }
  for (int j = 0; j < frames; ++j) {
    for (int i = 0; i < landmarks; ++i) {
      if (j < tracks[i].first || j >= tracks[i].second) continue;
      Vec3<double> z;
      Mat36<double> jp;
      Mat3<double> jl;
      pr.model.Predict(truth[j], points[i], &z, &jp, &jl);
      for (int k = 0; k < 3; ++k) z[k] += pr.sigma_z * g(rng);
      pr.obs.push_back({j, i, z});
    }
  }
  pr.first_pose = truth[0] + 0.01 * State::Random();
  pr.options.robust = false;
  pr.options.max_iterations = 5;
  pr.options.first_pose_sigma_m = 0.1;
  pr.options.first_pose_sigma_rad = 0.2;
  return pr;
}

// Independent dense batch: every pose and landmark, every factor, one linear solve.
template <int D>
struct Batch {
  Eigen::VectorXd x;
  Eigen::MatrixXd cov;
  int PoseIndex(int j) const { return D * j; }
  int LandmarkIndex(int i) const { return D * frames + 3 * i; }
  int frames = 0;
};

template <int D>
Batch<D> SolveBatch(const Problem<D>& pr, int last_frame) {
  const int nf = last_frame + 1;
  const int n = D * nf + 3 * pr.landmarks;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  // Prior on pose 0 around the initial estimate; information as the filter builds it.
  const Eigen::Matrix<double, D, 1> pi = pr.FirstStateInformation();
  h.block<D, D>(0, 0) += pi.asDiagonal();
  b.segment<D>(0) += pi.asDiagonal() * pr.first_pose;
  const double qi = 1 / (pr.sigma_q * pr.sigma_q);
  for (int j = 1; j < nf; ++j) {  // p_j - F p_j-1 = u_j
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(D, n);
    jac.block<D, D>(0, D * j).setIdentity();
    jac.block<D, D>(0, D * (j - 1)) = -pr.model.f;
    h += qi * jac.transpose() * jac;
    b += qi * jac.transpose() * pr.u[j];
  }
  std::vector<bool> seen(pr.landmarks, false);
  const double ri = 1 / (pr.sigma_z * pr.sigma_z);
  for (const Obs& o : pr.obs) {
    if (o.frame > last_frame) continue;
    seen[o.landmark] = true;
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(3, n);
    jac.block<3, 6>(0, D * o.frame) = pr.model.a_pose;
    jac.block<3, 3>(0, D * nf + 3 * o.landmark) = pr.model.a_landmark;
    h += ri * jac.transpose() * jac;
    b += ri * jac.transpose() * o.z;
  }
  for (int i = 0; i < pr.landmarks; ++i)  // unseen landmarks: decoupled placeholders
    if (!seen[i]) h.block<3, 3>(D * nf + 3 * i, D * nf + 3 * i) = Mat3<double>::Identity();
  Batch<D> out;
  out.frames = nf;
  out.cov = h.inverse();
  out.x = out.cov * b;
  return out;
}

// Runs the SWF with a window of `window` poses (kBatch: the capacity) over the first
// `last_frame + 1` frames and compares with the batch solution.
// One capacity serves every window size (the window is a run-time option), which keeps this
// file to one filter instantiation per D.
constexpr int kCapacity = 16;
template <int D, int P = 64>
using LinearSwf = SlidingWindowFilter<LinearModel<D>, kCapacity, 64, 64, P>;

// `batch_problem`: the measurements the filter is expected to have used, where it drops some
// (a full prior) and says so in `expected_faults`.
template <int D, int P = 64>
void ExpectEqualsBatch(const Problem<D>& pr, SwfMode mode, int window, int last_frame,
                       const Problem<D>* batch_problem = nullptr,
                       std::uint32_t expected_faults = 0u) {
  using Filter = LinearSwf<D, P>;
  using StateMat = Eigen::Matrix<double, D, D>;
  auto swf = std::make_unique<Filter>();
  SwfOptions options = pr.options;
  options.mode = mode;
  options.window_size = mode == SwfMode::kBatch ? kCapacity : window;
  ASSERT_EQ(swf->Configure(pr.model, options), core::Status::kOk);
  const StateMat q_sqrt = StateMat::Identity() / pr.sigma_q;
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / pr.sigma_z;
  std::size_t next = 0;
  for (int j = 0; j <= last_frame; ++j) {
    if (j == 0) {
      ASSERT_EQ(swf->AddPose(pr.first_pose), core::Status::kOk);
    } else {
      ASSERT_EQ(swf->AddPoseWithMotion(pr.u[j], q_sqrt), core::Status::kOk);
    }
    for (; next < pr.obs.size() && pr.obs[next].frame == j; ++next)
      ASSERT_EQ(swf->AddObservation(pr.obs[next].landmark, pr.obs[next].z, r_sqrt),
                core::Status::kOk);
    ASSERT_EQ(swf->Update(), core::Status::kOk) << "frame " << j;
    if (pr.covariances_each_frame) {
      ASSERT_EQ(swf->ComputeCovariances(), core::Status::kOk);
    }
  }
  const Batch<D> batch = SolveBatch(batch_problem ? *batch_problem : pr, last_frame);
  // The newest state's covariance alone (the factorization and the newest state's columns of
  // its inverse, nothing else): the block of the batch information matrix's dense inverse
  // within 1e-9, the tolerance of every block here (these covariances are 1e-4..1; two exact
  // inversions of a well-conditioned system differ by rounding, ~1e-15 of that), and the same
  // bits as the full ComputeCovariances gives it (same factor, same operations).
  ASSERT_EQ(swf->ComputeNewestCovariance(), core::Status::kOk);
  const StateMat newest_only = swf->NewestStateCovariance();
  const int newest_index = batch.PoseIndex(last_frame);
  EXPECT_LT((newest_only - batch.cov.template block<D, D>(newest_index, newest_index))
                .cwiseAbs()
                .maxCoeff(),
            1e-9);
  ASSERT_EQ(swf->ComputeCovariances(), core::Status::kOk);
  EXPECT_TRUE(newest_only == swf->NewestStateCovariance());
  const int np = swf->NumPoses();
  ASSERT_EQ(np, mode == SwfMode::kBatch ? last_frame + 1 : std::min(window, last_frame + 1));
  for (int j = 0; j < np; ++j) {
    const int frame = last_frame + 1 - np + j;
    const Eigen::Matrix<double, D, 1> expected =
        batch.x.template segment<D>(batch.PoseIndex(frame));
    EXPECT_LT((swf->PoseAt(j) - expected).cwiseAbs().maxCoeff(), 1e-9) << "pose " << frame;
    const StateMat expected_cov =
        batch.cov.template block<D, D>(batch.PoseIndex(frame), batch.PoseIndex(frame));
    EXPECT_LT((swf->StateCovariance(j) - expected_cov).cwiseAbs().maxCoeff(), 1e-9)
        << "state covariance " << frame;
    const Mat6<double> pose_block = swf->StateCovariance(j).template topLeftCorner<6, 6>();
    EXPECT_EQ(swf->PoseCovariance(j), pose_block);
  }
  int compared = 0;
  int compared_prior = 0;
  swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>& position, int) {
    const int index = batch.LandmarkIndex(static_cast<int>(id));
    EXPECT_LT((position - batch.x.template segment<3>(index)).cwiseAbs().maxCoeff(), 1e-9) << id;
    Mat3<double> cov;
    ASSERT_TRUE(swf->GetLandmarkCovariance(id, &cov));
    EXPECT_LT((cov - batch.cov.template block<3, 3>(index, index)).cwiseAbs().maxCoeff(), 1e-9)
        << id;
    ++compared;
  });
  compared_prior = swf->NumPriorLandmarks();
  EXPECT_EQ(swf->FaultBits(), expected_faults);  // no prior overflow unless one was built
  EXPECT_GT(compared, 5);
  if (mode != SwfMode::kBatch && last_frame + 1 > window) {
    // The interesting case: information reached these landmarks only through the prior.
    EXPECT_GT(compared_prior, 0);
  }
}

// Every test below runs for D = 6 (poses) and D = 15 (states with velocity and IMU biases
// beyond the pose: the same algebra).
template <typename Dim>
class SwfLinear : public ::testing::Test {};
using StateDims = ::testing::Types<std::integral_constant<int, 6>, std::integral_constant<int, 15>>;
struct StateDimName {
  template <typename Dim>
  static std::string GetName(int) {
    return Dim::value == 6 ? "Pose" : "ExtendedState";
  }
};
TYPED_TEST_SUITE(SwfLinear, StateDims, StateDimName);

TYPED_TEST(SwfLinear, BatchModeEqualsIndependentBatch) {
  constexpr int D = TypeParam::value;
  const Problem<D> pr = MakeProblem<D>(1, 12, 30, 2, 6);
  ExpectEqualsBatch(pr, SwfMode::kBatch, 0, 11);
}

TYPED_TEST(SwfLinear, SlidingWindowEqualsBatchForEveryWindowSize) {
  constexpr int D = TypeParam::value;
  for (std::uint64_t seed : {2u, 3u, 4u}) {
    const Problem<D> pr = MakeProblem<D>(seed, 14, 40, 1, 8);
    ExpectEqualsBatch(pr, SwfMode::kSlidingWindow, 1, 13);
    ExpectEqualsBatch(pr, SwfMode::kSlidingWindow, 2, 13);
    ExpectEqualsBatch(pr, SwfMode::kSlidingWindow, 3, 13);
    ExpectEqualsBatch(pr, SwfMode::kSlidingWindow, 5, 13);
    // Stopping at different frames changes which poses and landmarks were marginalized when.
    ExpectEqualsBatch(pr, SwfMode::kSlidingWindow, 4, 6);
    ExpectEqualsBatch(pr, SwfMode::kSlidingWindow, 4, 9);
  }
}

TYPED_TEST(SwfLinear, LongTracksFillThePriorAndStillMatch) {
  constexpr int D = TypeParam::value;
  const Problem<D> pr = MakeProblem<D>(5, 10, 20, 8, 10);  // landmarks live across many windows
  ExpectEqualsBatch(pr, SwfMode::kSlidingWindow, 2, 9);
  ExpectEqualsBatch(pr, SwfMode::kSlidingWindow, 3, 9);
}

// Landmarks seen once (a track lost at once) carry no information beyond themselves; those of
// the marginalized pose must not take prior slots. 12 of them per frame beside the tracks
// would overflow a prior of 10 landmarks if they entered it.
TYPED_TEST(SwfLinear, OneShotLandmarksTakeNoPriorSlot) {
  constexpr int D = TypeParam::value;
  Problem<D> pr = MakeProblem<D>(6, 8, 12, 3, 8);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 3.0);
  std::vector<Obs> merged;
  std::size_t next = 0;
  for (int j = 0; j < pr.frames; ++j) {
    for (; next < pr.obs.size() && pr.obs[next].frame == j; ++next) merged.push_back(pr.obs[next]);
    for (int k = 0; k < 12; ++k)
      merged.push_back({j, pr.landmarks++, Vec3<double>(g(rng), g(rng), g(rng))});
  }
  pr.obs = merged;
  ExpectEqualsBatch<D, 10>(pr, SwfMode::kSlidingWindow, 2, 7);
  ExpectEqualsBatch<D, 10>(pr, SwfMode::kSlidingWindow, 1, 7);
}

// A full prior takes the landmarks the window measures most. Each frame brings three
// two-frame tracks, listed before six tracks that span the run; the prior has room for six.
// Taken first come, the short tracks would fill it and every marginalized pose's sightings of
// the long tracks would be dropped. Taken by use, only the short tracks' first sightings from
// marginalized poses are dropped, and the filter equals the batch without exactly those.
TYPED_TEST(SwfLinear, AFullPriorKeepsTheLandmarksTheWindowMeasuresMost) {
  constexpr int D = TypeParam::value;
  constexpr int kLong = 6;
  constexpr int kShortPerFrame = 3;
  constexpr int kFrames = 9;
  constexpr int kWindow = 3;
  constexpr int kLastFrame = kFrames - 1;
  Problem<D> used = MakeProblem<D>(8, kFrames, 0, 1, 1);
  used.options.gate_probability = 0.0;  // random numbers, not sightings of one scene
  Problem<D> all = used;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> g(0.0, 3.0);
  const auto add = [&](int frame, int landmark, bool kept) {
    const Obs o{frame, landmark, Vec3<double>(g(rng), g(rng), g(rng))};
    all.obs.push_back(o);
    if (kept) used.obs.push_back(o);
  };
  const auto short_track = [](int start, int k) { return kLong + kShortPerFrame * start + k; };
  for (int j = 0; j < kFrames; ++j) {
    for (int k = 0; k < kShortPerFrame; ++k) {
      if (j > 0) add(j, short_track(j - 1, k), true);
      // A first sighting is dropped once its pose leaves the window.
      const bool marginalized = j < kLastFrame + 1 - kWindow;
      add(j, short_track(j, k), !marginalized);
    }
    for (int i = 0; i < kLong; ++i) add(j, i, true);
  }
  all.landmarks = used.landmarks = short_track(kFrames, 0);
  ExpectEqualsBatch<D, kLong>(all, SwfMode::kSlidingWindow, kWindow, kLastFrame, &used,
                              kFaultPriorCapacity);
}

// A corrupted first sighting (30 sigma off in each coordinate) alone places its landmark; the
// second, good sighting then fails the prediction gate. Neither is kept and the track starts
// again from its third sighting, so the filter equals the batch without those two sightings.
// Kept instead, the first would go on rejecting every later sighting.
TYPED_TEST(SwfLinear, ALandmarkWhoseTwoSightingsDisagreeStartsAgain) {
  constexpr int D = TypeParam::value;
  constexpr int kLastFrame = 11;
  Problem<D> all = MakeProblem<D>(9, kLastFrame + 1, 30, 6, 9);
  all.covariances_each_frame = true;
  std::vector<int> sightings(all.landmarks, 0);
  std::vector<int> first_frame(all.landmarks, -1);
  for (const Obs& o : all.obs) {
    if (sightings[o.landmark]++ == 0) first_frame[o.landmark] = o.frame;
  }
  int corrupted = -1;
  for (int i = 0; i < all.landmarks && corrupted < 0; ++i)
    if (first_frame[i] >= 1 && first_frame[i] + 5 <= kLastFrame && sightings[i] >= 5) corrupted = i;
  ASSERT_GE(corrupted, 0);
  Problem<D> used = all;
  used.obs.clear();
  int seen = 0;
  for (Obs& o : all.obs) {
    if (o.landmark != corrupted) {
      used.obs.push_back(o);
      continue;
    }
    if (seen == 0) o.z += Vec3<double>::Constant(30.0 * all.sigma_z);
    if (seen++ >= 2) used.obs.push_back(o);
  }
  ExpectEqualsBatch<D>(all, SwfMode::kSlidingWindow, 4, kLastFrame, &used);
}

// A window of one pose against a Kalman filter over [pose ; landmarks], written here in covariance
// form.
TYPED_TEST(SwfLinear, WindowOfOneEqualsKalmanFilter) {
  constexpr int D = TypeParam::value;
  using StateMat = Eigen::Matrix<double, D, D>;
  Problem<D> pr = MakeProblem<D>(7, 8, 10, 8, 8);
  // Every landmark observed in every frame so the filter state is fixed from frame 0.
  std::vector<Obs> all;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, pr.sigma_z);
  std::vector<Vec3<double>> points(pr.landmarks);
  for (auto& p : points) p = 4.0 * Vec3<double>::Random();
  typename Problem<D>::State pose = pr.first_pose;
  for (int j = 0; j < pr.frames; ++j) {
    if (j > 0) pose = pr.model.f * pose + pr.u[j];
    for (int i = 0; i < pr.landmarks; ++i) {
      Vec3<double> z;
      Mat36<double> a;
      Mat3<double> b;
      pr.model.Predict(pose, points[i], &z, &a, &b);
      all.push_back({j, i, z + Vec3<double>(g(rng), g(rng), g(rng))});
    }
  }
  pr.obs = all;

  const int n = D + 3 * pr.landmarks;
  const double ri = 1 / (pr.sigma_z * pr.sigma_z);
  auto measurement_jacobian = [&](int i) {
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(3, n);
    jac.block<3, 6>(0, 0) = pr.model.a_pose;
    jac.block<3, 3>(0, D + 3 * i) = pr.model.a_landmark;
    return jac;
  };
  // Frame 0 in information form (landmarks have no prior), then covariance form.
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  const Eigen::Matrix<double, D, 1> pi = pr.FirstStateInformation();
  info.block<D, D>(0, 0) += pi.asDiagonal();
  rhs.head<D>() += pi.asDiagonal() * pr.first_pose;
  for (const Obs& o : pr.obs) {
    if (o.frame != 0) continue;
    const Eigen::MatrixXd jac = measurement_jacobian(o.landmark);
    info += ri * jac.transpose() * jac;
    rhs += ri * jac.transpose() * o.z;
  }
  Eigen::MatrixXd cov = info.inverse();
  Eigen::VectorXd x = cov * rhs;

  auto swf = std::make_unique<LinearSwf<D>>();
  SwfOptions options = pr.options;
  options.window_size = 1;
  ASSERT_EQ(swf->Configure(pr.model, options), core::Status::kOk);
  const StateMat q_sqrt = StateMat::Identity() / pr.sigma_q;
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / pr.sigma_z;
  for (int j = 0; j < pr.frames; ++j) {
    if (j == 0) {
      ASSERT_EQ(swf->AddPose(pr.first_pose), core::Status::kOk);
    } else {
      ASSERT_EQ(swf->AddPoseWithMotion(pr.u[j], q_sqrt), core::Status::kOk);
      // Kalman predict.
      Eigen::MatrixXd f = Eigen::MatrixXd::Identity(n, n);
      f.block<D, D>(0, 0) = pr.model.f;
      x.head<D>() = pr.model.f * x.head<D>() + pr.u[j];
      cov = f * cov * f.transpose();
      cov.block<D, D>(0, 0) += pr.sigma_q * pr.sigma_q * StateMat::Identity();
      // Kalman update, one measurement at a time (equivalent for independent noise).
      for (const Obs& o : pr.obs) {
        if (o.frame != j) continue;
        const Eigen::MatrixXd h = measurement_jacobian(o.landmark);
        const Eigen::Matrix3d s =
            h * cov * h.transpose() + pr.sigma_z * pr.sigma_z * Mat3<double>::Identity();
        const Eigen::MatrixXd gain = cov * h.transpose() * s.inverse();
        x += gain * (o.z - h * x);
        cov = (Eigen::MatrixXd::Identity(n, n) - gain * h) * cov;
      }
    }
    for (const Obs& o : pr.obs) {
      if (o.frame == j) {
        ASSERT_EQ(swf->AddObservation(o.landmark, o.z, r_sqrt), core::Status::kOk);
      }
    }
    ASSERT_EQ(swf->Update(), core::Status::kOk);
    ASSERT_EQ(swf->ComputeCovariances(), core::Status::kOk);
    EXPECT_LT((swf->NewestPose() - x.head<D>()).cwiseAbs().maxCoeff(), 1e-9) << "frame " << j;
    EXPECT_LT((swf->NewestStateCovariance() - cov.block<D, D>(0, 0)).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((swf->NewestPoseCovariance() - cov.block<6, 6>(0, 0)).cwiseAbs().maxCoeff(), 1e-9);
    for (int i = 0; i < pr.landmarks; ++i) {
      Vec3<double> l;
      Mat3<double> lc;
      ASSERT_TRUE(swf->GetLandmark(i, &l));
      ASSERT_TRUE(swf->GetLandmarkCovariance(i, &lc));
      EXPECT_LT((l - x.segment<3>(D + 3 * i)).cwiseAbs().maxCoeff(), 1e-9);
      EXPECT_LT((lc - cov.block<3, 3>(D + 3 * i, D + 3 * i)).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

}  // namespace
}  // namespace swf::estimator
