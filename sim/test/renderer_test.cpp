#include "swf/sim/renderer.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <string>

#include "swf/sim/trajectory.hpp"
#include "swf/testing/shared_dir.hpp"

namespace swf::sim {
namespace {

using swf::testing::SharedDir;

RigOptions SmallRig() {
  RigOptions rig = EdlRig();
  rig.width_px = 192;
  rig.height_px = 144;
  return rig;
}

struct Scene {
  Terrain terrain;
  Appearance appearance;
};

void MakeScene(const TerrainOptions& t, const AppearanceOptions& a, Scene* scene) {
  ASSERT_EQ(scene->terrain.Configure(t), core::Status::kOk);
  ASSERT_EQ(scene->appearance.Configure(scene->terrain, a), core::Status::kOk);
}

estimator::Pose<double> NadirAt(double x, double y, double z) {
  estimator::Pose<double> pose;
  pose.R = NadirRotation(0.0);
  pose.t = {x, y, z};
  return pose;
}

// Configures `renderer` with `options` and renders the scene's frame 0 from `pose` into `im`.
void ConfigureAndRender(Renderer* renderer, const RenderOptions& options, const Scene& scene,
                        const estimator::Pose<double>& pose, StereoImages* im) {
  ASSERT_EQ(renderer->Configure(options), core::Status::kOk);
  ASSERT_EQ(renderer->Render(scene.terrain, scene.appearance, pose, 0, im), core::Status::kOk);
}

// The disparity in [lo, hi] (0.05 px steps, linear interpolation) whose 9x9 right patch has the
// smallest SSD against the left patch at (u, v).
double MatchedDisparity(const StereoImages& im, int u, int v, double lo, double hi) {
  double best_d = 0.0;
  double best_cost = 1e300;
  for (double d = lo; d <= hi; d += 0.05) {
    double cost = 0.0;
    for (int dv = -4; dv <= 4; ++dv) {
      for (int du = -4; du <= 4; ++du) {
        const double x = u + du - d;
        const int x0 = static_cast<int>(std::floor(x));
        const double f = x - x0;
        const double right = (1 - f) * im.right[(v + dv) * im.width + x0] +
                             f * im.right[(v + dv) * im.width + x0 + 1];
        const double diff = im.left[(v + dv) * im.width + u + du] - right;
        cost += diff * diff;
      }
    }
    if (cost < best_cost) {
      best_cost = cost;
      best_d = d;
    }
  }
  return best_d;
}

TEST(RendererTest, TrueDisparityOfATiltedPlaneIsAnalytic) {
  // GIVEN a tilted plane z = a x + b y and a nadir camera at height H.
  TerrainOptions t;
  t.size = 512;
  t.relief_rms_m = 0.0;
  t.tilt_x = 0.08;
  t.tilt_y = 0.03;
  Scene scene;
  ASSERT_NO_FATAL_FAILURE(MakeScene(t, AppearanceOptions{}, &scene));
  RenderOptions r;
  r.rig = SmallRig();
  const double height = 20.0;
  Renderer renderer;
  StereoImages images;
  ASSERT_NO_FATAL_FAILURE(ConfigureAndRender(&renderer, r, scene, NadirAt(0, 0, height), &images));
  const auto& cam = renderer.Camera();
  for (const auto& [u, v] : {std::pair{10, 10}, {96, 72}, {180, 130}, {40, 120}}) {
    // Camera ray in the world: (xn, -yn, -1); solve H - s = a xn s - b yn s.
    const double xn = (u - cam.cx) / cam.fx;
    const double yn = (v - cam.cy) / cam.fy;
    const double depth = height / (1.0 + t.tilt_x * xn - t.tilt_y * yn);
    const double disparity = cam.fx * cam.baseline_m / depth;
    EXPECT_NEAR(images.disparity_px[v * images.width + u], disparity, 0.05 * 0.01);
    EXPECT_NEAR(images.depth_m[v * images.width + u], depth, 1e-4);
  }
}

TEST(RendererTest, RenderedImagesAgreeWithTheTrueDisparity) {
  // GIVEN textured, rough terrain and a noise-free render.
  TerrainOptions t = TerrainPresetOptions(TerrainPreset::kCraterField, 5);
  t.size = 512;
  AppearanceOptions a = DefaultImagery(SharedDir());
  Scene scene;
  ASSERT_NO_FATAL_FAILURE(MakeScene(t, a, &scene));
  RenderOptions r;
  r.rig = SmallRig();
  r.add_noise = false;
  Renderer renderer;
  StereoImages im;
  ASSERT_NO_FATAL_FAILURE(ConfigureAndRender(&renderer, r, scene, NadirAt(1, 2, 15), &im));
  // WHEN a 9x9 patch of the left image is matched along the right image row THEN the best
  // disparity is the true one at the patch centre.
  int checked = 0;
  for (int v = 20; v < im.height - 20; v += 25) {
    for (int u = 40; u < im.width - 20; u += 25) {
      const double d_true = im.disparity_px[v * im.width + u];
      EXPECT_NEAR(MatchedDisparity(im, u, v, d_true - 1.5, d_true + 1.5), d_true, 0.3)
          << "at " << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 10);
}

// GIVEN the same scene rendered with the calibrated rig, with the true right camera 10 cm further
// out (baseline error) and with it turned 5 mrad about its y axis (rotation error) WHEN the left
// patches are matched in the right images THEN the left image and the calibration (Camera()) are
// unchanged, the baseline error scales every disparity by (b + db) / b and the rotation about y
// adds fx * angle to every disparity: the right image is the true camera's.
TEST(RendererTest, TheTrueRightCameraCarriesTheCalibrationError) {
  TerrainOptions t = TerrainPresetOptions(TerrainPreset::kCraterField, 5);
  t.size = 512;
  Scene scene;
  ASSERT_NO_FATAL_FAILURE(MakeScene(t, DefaultImagery(SharedDir()), &scene));
  RenderOptions nominal;
  nominal.rig = SmallRig();
  nominal.add_noise = false;
  RenderOptions wide = nominal;
  wide.baseline_error_m = 0.1;
  RenderOptions turned = nominal;
  turned.right_rotation_error_rad = Eigen::Vector3d(0.0, 0.005, 0.0);
  StereoImages images[3];
  const RenderOptions* options[3] = {&nominal, &wide, &turned};
  for (int i = 0; i < 3; ++i) {
    Renderer renderer;
    ASSERT_NO_FATAL_FAILURE(
        ConfigureAndRender(&renderer, *options[i], scene, NadirAt(1, 2, 15), &images[i]));
    EXPECT_EQ(renderer.Camera().baseline_m, 1.0);
  }
  EXPECT_EQ(images[1].left, images[0].left);
  EXPECT_EQ(images[2].left, images[0].left);
  EXPECT_NE(images[1].right, images[0].right);
  const double fx = MakeStereoCamera(nominal.rig).fx;
  int checked = 0;
  for (int v = 20; v < images[0].height - 20; v += 25) {
    for (int u = 50; u < images[0].width - 20; u += 25) {
      const double d_true = images[0].disparity_px[v * images[0].width + u];
      const double d_wide = d_true * 1.1;
      const double d_turned = d_true + fx * 0.005;
      EXPECT_NEAR(MatchedDisparity(images[1], u, v, d_wide - 1.5, d_wide + 1.5), d_wide, 0.3)
          << "at " << u << "," << v;
      EXPECT_NEAR(MatchedDisparity(images[2], u, v, d_turned - 1.5, d_turned + 1.5), d_turned, 0.3)
          << "at " << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 10);
  RenderOptions bad = nominal;
  bad.baseline_error_m = -1.0;  // no baseline left
  Renderer renderer;
  EXPECT_EQ(renderer.Configure(bad), core::Status::kInvalidArgument);
}

TEST(RendererTest, TrueLandmarkProjectsOntoItsPlantedFiducial) {
  TerrainOptions t = TerrainPresetOptions(TerrainPreset::kSmoothPlains, 2);
  t.size = 512;
  t.rocks.k = 0.0;
  Scene scene;
  ASSERT_NO_FATAL_FAILURE(
      MakeScene(t, AppearanceOptions{}, &scene));  // uniform albedo: only the fiducial has contrast
  const estimator::Pose<double> pose = NadirAt(0.3, -0.2, 12.0);
  RenderOptions r;
  r.rig = SmallRig();
  r.add_noise = false;
  Renderer renderer;
  ASSERT_EQ(renderer.Configure(r), core::Status::kOk);
  // Plant a fiducial where the left pixel (70.3, 50.6) looks; its centre is the landmark.
  const auto& cam = renderer.Camera();
  const Eigen::Vector3d dir =
      pose.R * Eigen::Vector3d((70.3 - cam.cx) / cam.fx, (50.6 - cam.cy) / cam.fy, 1.0);
  double s = 0.0;
  ASSERT_TRUE(scene.terrain.Intersect(pose.t, dir, &s));
  const Eigen::Vector3d landmark = pose.t + s * dir;
  r.fiducials.push_back({landmark.head<2>(), 0.012, 0.9});  // ~2.3 px sigma at 12 m
  ASSERT_EQ(renderer.Configure(r), core::Status::kOk);
  StereoImages im;
  ASSERT_EQ(renderer.Render(scene.terrain, scene.appearance, pose, 0, &im), core::Status::kOk);
  StereoImages plain;
  r.fiducials.clear();
  Renderer no_fiducial;
  ASSERT_EQ(no_fiducial.Configure(r), core::Status::kOk);
  ASSERT_EQ(no_fiducial.Render(scene.terrain, scene.appearance, pose, 0, &plain),
            core::Status::kOk);
  const Eigen::Vector3d z = cam.Project(pose.ApplyInverse(landmark));
  // Centroid of the darkening (plain - fiducial) around the projection, in each image.
  auto centroid = [&](const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b,
                      double u0, double v0) {
    double sw = 0.0;
    double su = 0.0;
    double sv = 0.0;
    for (int v = static_cast<int>(v0) - 12; v <= static_cast<int>(v0) + 12; ++v) {
      for (int u = static_cast<int>(u0) - 12; u <= static_cast<int>(u0) + 12; ++u) {
        const double w = static_cast<double>(b[v * im.width + u]) - a[v * im.width + u];
        sw += w;
        su += w * u;
        sv += w * v;
      }
    }
    return Eigen::Vector2d(su / sw, sv / sw);
  };
  const Eigen::Vector2d left = centroid(im.left, plain.left, z.x(), z.z());
  const Eigen::Vector2d right = centroid(im.right, plain.right, z.y(), z.z());
  EXPECT_NEAR(left.x(), z.x(), 0.1);
  EXPECT_NEAR(left.y(), z.z(), 0.1);
  EXPECT_NEAR(right.x(), z.y(), 0.1);
  EXPECT_NEAR(right.y(), z.z(), 0.1);
  EXPECT_NEAR(z.x(), 70.3, 1e-6);
}

TEST(RendererTest, TileStartHeightsNeverSkipAHit) {
  // GIVEN rock-field terrain seen low and oblique (30 deg off nadir: rocks occlude ground), where
  // the renderer walks each 8 x 8 tile's rays only between the tile's local height bounds.
  TerrainOptions t = TerrainPresetOptions(TerrainPreset::kRockField, 4);
  t.size = 512;
  Scene scene;
  ASSERT_NO_FATAL_FAILURE(MakeScene(t, AppearanceOptions{}, &scene));
  RenderOptions r;
  r.rig = SmallRig();
  r.add_noise = false;
  estimator::Pose<double> pose = NadirAt(2.0, -3.0, 6.0);
  pose.R = Eigen::AngleAxisd(0.52, Eigen::Vector3d::UnitX()).toRotationMatrix() * pose.R;
  Renderer renderer;
  StereoImages im;
  ASSERT_NO_FATAL_FAILURE(ConfigureAndRender(&renderer, r, scene, pose, &im));
  // THEN every pixel's depth is the first hit of a ray cast from the global maximum.
  const auto& cam = renderer.Camera();
  int finite = 0;
  for (int v = 0; v < im.height; ++v) {
    for (int u = 0; u < im.width; ++u) {
      const Eigen::Vector3d dir =
          pose.R * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      double s = 0.0;
      const bool hit = scene.terrain.Intersect(pose.t, dir, &s);
      const float depth = im.depth_m[v * im.width + u];
      ASSERT_EQ(hit, std::isfinite(depth)) << u << "," << v;
      if (!hit) continue;
      ++finite;
      ASSERT_NEAR(s, depth, 1e-6 * s) << u << "," << v;  // float depth, same surface point
    }
  }
  EXPECT_GT(finite, im.width * im.height / 2);
}

TEST(RendererTest, SameSeedGivesBitIdenticalImages) {
  TerrainOptions t = TerrainPresetOptions(TerrainPreset::kRockField, 9);
  t.size = 512;
  AppearanceOptions a = DefaultImagery(SharedDir());
  Scene s1;
  Scene s2;
  ASSERT_NO_FATAL_FAILURE(MakeScene(t, a, &s1));
  ASSERT_NO_FATAL_FAILURE(MakeScene(t, a, &s2));
  RenderOptions r;
  r.rig = SmallRig();
  r.samples_per_pixel = 4;
  Renderer r1;
  Renderer r2;
  ASSERT_EQ(r1.Configure(r), core::Status::kOk);
  ASSERT_EQ(r2.Configure(r), core::Status::kOk);
  StereoImages i1;
  StereoImages i2;
  ASSERT_EQ(r1.Render(s1.terrain, s1.appearance, NadirAt(0, 0, 30), 7, &i1), core::Status::kOk);
  ASSERT_EQ(r2.Render(s2.terrain, s2.appearance, NadirAt(0, 0, 30), 7, &i2), core::Status::kOk);
  EXPECT_EQ(i1.left, i2.left);
  EXPECT_EQ(i1.right, i2.right);
  EXPECT_EQ(0, std::memcmp(i1.depth_m.data(), i2.depth_m.data(), i1.depth_m.size() * 4));
  // The next frame's noise differs.
  ASSERT_EQ(r2.Render(s2.terrain, s2.appearance, NadirAt(0, 0, 30), 8, &i2), core::Status::kOk);
  EXPECT_NE(i1.left, i2.left);
}

// GIVEN flat, evenly lit ground WHEN rendered with the default camera and with a darker exposure,
// more read noise and a lower gain (electrons per DN) THEN each image's mean is its exposure and
// its spread the modelled read + shot noise (+ quantization).
TEST(RendererTest, PhotometricNoiseHasTheModelledSigma) {
  TerrainOptions t;
  t.size = 256;
  t.relief_rms_m = 0.0;
  AppearanceOptions a;
  a.detail_strength = 0.0;
  a.sun_elevation_deg = 90.0;
  Scene scene;
  ASSERT_NO_FATAL_FAILURE(MakeScene(t, a, &scene));
  RenderOptions dispersed;
  dispersed.exposure_dn = 60.0;
  dispersed.read_noise_e = 40.0;
  dispersed.electrons_per_dn = 10.0;
  for (RenderOptions r : {RenderOptions{}, dispersed}) {
    r.rig = SmallRig();
    Renderer renderer;
    StereoImages im;
    ASSERT_NO_FATAL_FAILURE(ConfigureAndRender(&renderer, r, scene, NadirAt(0, 0, 10), &im));
    double sum = 0.0;
    double sum2 = 0.0;
    for (std::uint8_t p : im.left) {
      sum += p;
      sum2 += static_cast<double>(p) * p;
    }
    const double n = static_cast<double>(im.left.size());
    const double mean = sum / n;
    const double sigma = std::sqrt(sum2 / n - mean * mean);
    EXPECT_NEAR(mean, r.exposure_dn, 0.2);
    const double expected = std::sqrt(std::pow(r.read_noise_e / r.electrons_per_dn, 2) +
                                      r.exposure_dn / r.electrons_per_dn + 1.0 / 12.0);
    EXPECT_NEAR(sigma, expected, 0.05 * expected) << r.exposure_dn;
  }
}

TEST(RendererTest, RejectsBadOptions) {
  Renderer renderer;
  RenderOptions r;
  r.samples_per_pixel = 3;
  EXPECT_EQ(renderer.Configure(r), core::Status::kInvalidArgument);
  Terrain t;
  Appearance a;
  StereoImages im;
  EXPECT_EQ(renderer.Render(t, a, NadirAt(0, 0, 1), 0, &im), core::Status::kNotConfigured);
}

TEST(RendererTest, MissingImageryIsAClearErrorAndTheSceneIsRefused) {
  // GIVEN imagery paths that do not exist.
  TerrainOptions t;
  t.size = 64;
  Terrain terrain;
  ASSERT_EQ(terrain.Configure(t), core::Status::kOk);
  Appearance appearance;
  // WHEN the appearance is configured THEN it says so, and a render with it is refused.
  EXPECT_NE(appearance.Configure(terrain, DefaultImagery("/nonexistent")), core::Status::kOk);
  EXPECT_EQ(appearance.Size(), 0);
  RenderOptions r;
  r.rig = SmallRig();
  Renderer renderer;
  ASSERT_EQ(renderer.Configure(r), core::Status::kOk);
  StereoImages im;
  EXPECT_EQ(renderer.Render(terrain, appearance, NadirAt(0, 0, 10), 0, &im),
            core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::sim
