// swf-vo's library without Ceres: the loader's refusals (each names file and line), the sizing of
// filter instances (exact: one landmark or prior slot less and the filter refuses), the choice of
// an instance and its refusal beyond memory, the JSON output, the generator.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "kitti_vo.hpp"
#include "kitti_vo_instance.hpp"
#include "kitti_vo_synth.hpp"

namespace swf::tools {
namespace {

using estimator::Pose;
using estimator::Vec3;

estimator::StereoCamera<double> KittiCamera() {
  estimator::StereoCamera<double> c;
  c.fx = c.fy = 721.5377;
  c.cx = 609.5593;
  c.cy = 172.854;
  c.baseline_m = 0.537150588;
  return c;
}

// A small generated problem written to files whose lines the tests then edit.
class LoaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "kitti_vo_test_" + std::to_string(getpid()) + "_";
    KittiLikeOptions o;
    o.poses = 6;
    o.landmarks = 60;
    o.observations = 180;
    std::string error;
    ASSERT_TRUE(GenerateKittiLike(KittiCamera(), o, &generated_, nullptr, &error)) << error;
    ASSERT_TRUE(
        WriteKittiVo(generated_, Path("calib.txt"), Path("poses.txt"), Path("factors.txt"), &error))
        << error;
    std::ifstream in(Path("factors.txt"));
    for (std::string line; std::getline(in, line);) factor_lines_.push_back(line);
  }
  void TearDown() override {
    for (const char* f : {"calib.txt", "poses.txt", "factors.txt"}) std::remove(Path(f).c_str());
  }
  std::string Path(const std::string& name) const { return dir_ + name; }
  void WriteFactors(const std::vector<std::string>& lines) const {
    std::ofstream out(Path("factors.txt"));
    for (const std::string& l : lines) out << l << "\n";
  }
  // Loads; returns the error ("" on success).
  std::string Load(KittiVoProblem* problem) const {
    std::string error;
    return LoadKittiVo(Path("calib.txt"), Path("poses.txt"), Path("factors.txt"), problem, &error)
               ? ""
               : error;
  }

  std::string dir_;
  KittiVoProblem generated_;
  std::vector<std::string> factor_lines_;
};

TEST_F(LoaderTest, ReadsWhatTheGeneratorWrote) {
  KittiVoProblem loaded;
  ASSERT_EQ(Load(&loaded), "");
  ASSERT_EQ(loaded.poses.size(), generated_.poses.size());
  ASSERT_EQ(loaded.factors.size(), generated_.factors.size());
  for (std::size_t i = 0; i < loaded.factors.size(); ++i) {
    EXPECT_EQ(loaded.factors[i].pose, generated_.factors[i].pose);
    EXPECT_EQ(loaded.factors[i].landmark, generated_.factors[i].landmark);
    EXPECT_EQ(loaded.factors[i].line, generated_.factors[i].line);
    EXPECT_EQ(loaded.factors[i].z, generated_.factors[i].z);  // %.17g round-trips exactly
  }
  for (std::size_t j = 0; j < loaded.poses.size(); ++j)
    EXPECT_LT((loaded.poses[j].t - generated_.poses[j].t).norm(), 1e-15);
}

// A repeated line used to be fed once to the filter and counted twice in final_cost.
TEST_F(LoaderTest, RefusesADuplicateFactorNamingBothLines) {
  std::vector<std::string> lines = factor_lines_;
  lines.push_back(lines[4]);
  WriteFactors(lines);
  std::istringstream first(lines[4]);
  std::string pose;
  std::string landmark;
  first >> pose >> landmark;
  KittiVoProblem problem;
  const std::string want = Path("factors.txt") + ":" + std::to_string(lines.size()) +
                           ": duplicate factor: pose " + pose + " already observes landmark " +
                           landmark + " on line 5";
  EXPECT_EQ(Load(&problem), want);
}

// uL < uR (the columns swapped) used to be fed to the filter as a measurement.
TEST_F(LoaderTest, RefusesANonPositiveDisparity) {
  std::vector<std::string> lines = factor_lines_;
  std::istringstream ls(lines[2]);
  std::string pose, landmark, ul, ur, rest;
  ls >> pose >> landmark >> ul >> ur;
  std::getline(ls, rest);
  lines[2] = pose + " " + landmark + " " + ur + " " + ul + rest;
  WriteFactors(lines);
  KittiVoProblem problem;
  const std::string error = Load(&problem);
  EXPECT_EQ(error.rfind(Path("factors.txt") + ":3: disparity uL - uR = -", 0), 0u) << error;
  EXPECT_NE(error.find("is not positive (uL and uR swapped?)"), std::string::npos) << error;
}

// An empty factors file used to reach the solver and come back as "numerical failure"; it is
// refused naming the file as a whole (no line number).
TEST_F(LoaderTest, RefusesAnEmptyFactorsFile) {
  WriteFactors({});
  KittiVoProblem problem;
  EXPECT_EQ(Load(&problem), Path("factors.txt") + ": no factors in the file (0 lines)");
}

TEST_F(LoaderTest, RefusesAPoseWithoutFactors) {
  std::vector<std::string> kept;
  for (const std::string& l : factor_lines_)
    if (l.rfind("4 ", 0) != 0) kept.push_back(l);  // every factor of pose id 4
  WriteFactors(kept);
  KittiVoProblem problem;
  EXPECT_EQ(Load(&problem), Path("poses.txt") + ":4: pose id 4 has no factor in " +
                                Path("factors.txt") + ": nothing constrains it");
}

// A pose whose landmarks no other pose sees used to end in "numerical failure".
TEST_F(LoaderTest, RefusesAPoseNotLinkedToTheFirst) {
  std::vector<std::string> lines;
  for (const std::string& l : factor_lines_) {
    std::istringstream ls(l);
    std::string pose, landmark, rest;
    ls >> pose >> landmark;
    std::getline(ls, rest);
    lines.push_back(pose == "3" ? pose + " 9" + landmark + rest : l);  // pose 3's own landmarks
  }
  WriteFactors(lines);
  KittiVoProblem problem;
  EXPECT_EQ(Load(&problem), Path("poses.txt") +
                                ":3: pose id 3 shares no landmark, directly or through other "
                                "poses, with the first pose: nothing ties it to the fixed gauge");
}

// ---- sizing ----------------------------------------------------------------------------------

// Six poses 1 m apart; five clusters of three points (A B C D E = 0 1 2 3 4) seen from
//   pose  0: A C   1: A B   2: B C   3: B E   4: B D E   5: D E
// With a window of 2 the filter holds poses j-2..j after adding pose j: the most landmarks at
// once are 4 clusters (poses 1-3 and 2-4): 12. Marginalizing pose 1 puts A and B (seen from 1)
// in the prior, where C already is (it entered with pose 0 and the window still sees it from 2):
// 9, the most of any marginalization (pose 0: A C; 2: B C; 3: B E).
KittiVoProblem Clusters() {
  KittiVoProblem p;
  p.camera = KittiCamera();
  p.factors_path = "clusters";
  const std::vector<std::vector<int>> seen = {{0, 2}, {0, 1}, {1, 2}, {1, 4}, {1, 3, 4}, {3, 4}};
  const Vec3<double> offset[3] = {{0, 0, 0}, {1.5, 0.5, 2}, {0.3, -1.2, 4}};  // not collinear
  for (int j = 0; j < 6; ++j) {
    p.pose_ids.push_back(j + 1);
    p.poses.push_back(Pose<double>{Eigen::Matrix3d::Identity(), Vec3<double>(0, 0, j)});
    for (int cluster : seen[j]) {
      for (int k = 0; k < 3; ++k) {
        const Vec3<double> world = Vec3<double>(-4.0 + 3.0 * cluster, 0.0, 20.0) + offset[k];
        KittiFactor f;
        f.pose = j;
        f.landmark = 10 * cluster + k;
        f.z = p.camera.Project(p.poses[j].ApplyInverse(world));
        f.line = static_cast<int>(p.factors.size()) + 1;
        p.factors.push_back(f);
      }
    }
  }
  return p;
}

TEST(KittiVoNeeds, CountsPosesLandmarksFactorsAndPriorLandmarks) {
  const KittiVoCapacity batch = KittiVoNeeds(Clusters(), 0);
  EXPECT_EQ(batch.window_poses, 6);
  EXPECT_EQ(batch.landmarks, 15);
  EXPECT_EQ(batch.factors_per_pose, 9);
  EXPECT_EQ(batch.prior_landmarks, 1);
  const KittiVoCapacity window = KittiVoNeeds(Clusters(), 2);
  EXPECT_EQ(window.window_poses, 2);
  EXPECT_EQ(window.landmarks, 12);
  EXPECT_EQ(window.factors_per_pose, 9);
  EXPECT_EQ(window.prior_landmarks, 9);
  // A window as long as the sequence never marginalizes: the batch's needs.
  EXPECT_EQ(KittiVoNeeds(Clusters(), 6).prior_landmarks, 1);
}

template <int K, int N, int M, int P>
KittiVoResult SolveWithCapacity(const KittiVoProblem& problem, int window) {
  using Filter = estimator::SlidingWindowFilter<estimator::StereoModel<double>, K, N, M, P>;
  auto filter = std::make_unique<Filter>();
  return detail::SolveWith(filter.get(), problem, window);
}

// The needs are exact: the filter solves with them and refuses with one slot less.
TEST(KittiVoNeeds, AreExactlyWhatTheFilterUses) {
  const KittiVoProblem problem = Clusters();
  const KittiVoResult fits = SolveWithCapacity<2, 12, 9, 9>(problem, 2);
  ASSERT_TRUE(fits.ok) << fits.error;
  EXPECT_EQ(fits.fault_bits & estimator::kFaultPriorCapacity, 0u);
  EXPECT_LT(fits.final_cost, 1e-12);  // exact measurements, exact initial poses

  const KittiVoResult short_of_landmarks = SolveWithCapacity<2, 11, 9, 9>(problem, 2);
  EXPECT_FALSE(short_of_landmarks.ok);
  EXPECT_EQ(short_of_landmarks.error,
            "clusters:24: factor refused (pose id 4, landmark 42): full (this instance holds 11 "
            "active landmarks)");

  const KittiVoResult short_of_prior = SolveWithCapacity<2, 12, 9, 8>(problem, 2);
  EXPECT_NE(short_of_prior.fault_bits & estimator::kFaultPriorCapacity, 0u);
}

// A numerical failure names the update, its window and the fault. Pose 6 (index 5) here sees
// only landmarks of its own: the loader refuses that, so the problem is built in memory.
TEST(KittiVoSolver, NamesTheUpdateThatFailedNumerically) {
  KittiVoProblem problem = Clusters();
  for (KittiFactor& f : problem.factors)
    if (f.pose == 5) f.landmark += 1000;
  const KittiVoResult batch = SolveKittiVo(problem, 0);
  EXPECT_EQ(batch.error,
            "batch solve over 6 poses failed: numerical failure (fault bits 1: not positive "
            "definite)");
  const KittiVoResult window = SolveKittiVo(problem, 2);
  EXPECT_EQ(window.error,
            "update at pose id 6 (window of poses 5..6) failed: numerical failure (fault bits 1: "
            "not positive definite)");
}

// ---- choosing an instance --------------------------------------------------------------------

KittiVoCapacity Kitti00Needs() { return KittiVoCapacity{77, 15638, 687, 1}; }

// A copy: KittiVoTiers() returns a temporary (a reference into it dangled: ASan, debug preset).
KittiVoTierInfo Tier(const KittiVoPlan& plan) { return KittiVoTiers()[plan.tier]; }

TEST(KittiVoPlan, PicksTheSmallestInstanceThatHoldsTheProblem) {
  const KittiVoPlan plan = PlanKittiVo(Kitti00Needs(), 0);
  ASSERT_TRUE(plan.ok) << plan.error;
  const KittiVoCapacity c = Tier(plan).capacity;
  EXPECT_GE(c.window_poses, 77);
  EXPECT_GE(c.landmarks, 15638);
  EXPECT_GE(c.factors_per_pose, 687);
  for (int i = 0; i < plan.tier; ++i) {  // every smaller instance misses a count
    const KittiVoCapacity s = KittiVoTiers()[i].capacity;
    EXPECT_TRUE(s.window_poses < 77 || s.landmarks < 15638 || s.factors_per_pose < 687)
        << KittiVoTiers()[i].name;
  }
}

TEST(KittiVoPlan, RefusesOnlyBeyondAvailableMemory) {
  const KittiVoPlan fits = PlanKittiVo(Kitti00Needs(), 0);
  ASSERT_TRUE(fits.ok);
  const std::size_t bytes = Tier(fits).bytes;
  EXPECT_TRUE(PlanKittiVo(Kitti00Needs(), bytes).ok);
  const KittiVoPlan refused = PlanKittiVo(Kitti00Needs(), bytes - 1);
  EXPECT_FALSE(refused.ok);
  EXPECT_NE(refused.error.find("needs a filter instance of"), std::string::npos) << refused.error;
  EXPECT_NE(refused.error.find(Tier(fits).name), std::string::npos) << refused.error;
  EXPECT_NE(refused.error.find("of memory is available"), std::string::npos) << refused.error;
}

TEST(KittiVoPlan, NamesTheCountNoInstanceReaches) {
  KittiVoCapacity needs = Kitti00Needs();
  needs.window_poses = 100000;
  const KittiVoPlan plan = PlanKittiVo(needs, 0);
  EXPECT_FALSE(plan.ok);
  EXPECT_NE(plan.error.find("100000 window poses > "), std::string::npos) << plan.error;
}

TEST(KittiVoSolver, RefusesClearlyWhenMemoryIsShort) {
  KittiVoSolver solver;
  solver.SetAvailableMemoryForTesting(1000000);  // 1 MB: less than any instance
  const KittiVoResult r = solver.Solve(Clusters(), 0);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("but only 1 MB of memory is available"), std::string::npos) << r.error;
}

TEST(KittiVoSolver, SolvesWithTheInstanceItPicked) {
  const KittiVoResult r = SolveKittiVo(Clusters(), 2);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.needs.prior_landmarks, 9);
  EXPECT_EQ(r.instance.name, KittiVoTiers()[PlanKittiVo(r.needs, 0).tier].name);
  EXPECT_LT(r.final_cost, 1e-12);
}

// ---- output ----------------------------------------------------------------------------------

TEST(KittiVoReport, WritesNullForNumbersThatAreNotFinite) {
  const KittiVoProblem problem = Clusters();
  KittiVoResult r;
  r.ok = true;
  r.initial_cost = std::numeric_limits<double>::infinity();
  r.final_cost = std::numeric_limits<double>::quiet_NaN();
  r.poses = problem.poses;
  r.poses[1].t.x() = -std::numeric_limits<double>::infinity();
  const std::string json = KittiVoReport(problem, r, 0).dump();
  EXPECT_EQ(json.find("inf"), std::string::npos) << json;
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
  EXPECT_NE(json.find("\"initial_cost\":null,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"final_cost\":null,"), std::string::npos) << json;
  EXPECT_NE(json.find("[1.0,0.0,0.0,null,0.0,1.0,0.0,0.0,"), std::string::npos)
      << json;  // pose id 2
}

// ---- the generator ---------------------------------------------------------------------------

TEST(KittiLike, HasTheStatisticsOfKittiSequence00AndIsDeterministic) {
  KittiVoProblem a;
  KittiVoProblem b;
  std::vector<Pose<double>> truth;
  std::string error;
  ASSERT_TRUE(GenerateKittiLike(KittiCamera(), KittiLikeOptions{}, &a, &truth, &error)) << error;
  ASSERT_TRUE(GenerateKittiLike(KittiCamera(), KittiLikeOptions{}, &b, nullptr, &error)) << error;
  ASSERT_EQ(a.poses.size(), 77u);
  ASSERT_EQ(a.factors.size(), 52544u);
  const KittiVoCapacity needs = KittiVoNeeds(a, 0);
  EXPECT_EQ(needs.landmarks, 15638);
  std::vector<int> per_pose(77, 0);
  for (const KittiFactor& f : a.factors) ++per_pose[f.pose];
  for (int j = 0; j < 77; ++j) {  // ~680 per pose, as the real sequence
    EXPECT_GE(per_pose[j], 650) << j;
    EXPECT_LE(per_pose[j], 720) << j;
  }
  double travelled = 0.0;
  for (int j = 1; j < 77; ++j) travelled += (truth[j].t - truth[j - 1].t).norm();
  EXPECT_NEAR(travelled / 76.0, 1.0, 0.05);
  for (const KittiFactor& f : a.factors) {  // in the image, positive disparity
    EXPECT_GT(f.z.x() - f.z.y(), 0.0);
    EXPECT_GT(f.z.z(), -5.0);
    EXPECT_LT(f.z.z(), 381.0);
  }
  ASSERT_EQ(a.factors.size(), b.factors.size());
  for (std::size_t i = 0; i < a.factors.size(); ++i) ASSERT_EQ(a.factors[i].z, b.factors[i].z);
  // The initial poses drift from the truth (not a solved problem), the gauge does not.
  EXPECT_EQ((a.poses[0].t - truth[0].t).norm(), 0.0);
  EXPECT_GT((a.poses[76].t - truth[76].t).norm(), 0.01);
}

}  // namespace
}  // namespace swf::tools
