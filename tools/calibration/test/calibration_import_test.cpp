// The calibration importers on the real calibrations of /work/shared/data (EuRoC V1_01's
// sensor.yaml, KITTI's calib.txt), on one hand-made rig written in every format (test/data), and
// on one malformed file per refusal.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "swf/calibration/calibration_import.hpp"
#include "swf/image_io/image_io.hpp"
#include "swf/testing/files.hpp"
#include "swf/testing/shared_dir.hpp"

namespace swf::calibration {
namespace {

using swf::testing::ReadText;

std::string DataDir() { return std::string(SWF_CALIBRATION_TEST_DATA) + "/"; }
std::string SharedData() { return swf::testing::SharedDir() + "/data/"; }

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

RectifiedPair Rectified(const std::vector<std::string>& files, const ImportOptions& options = {}) {
  StereoCalibration c;
  std::string error;
  EXPECT_TRUE(ImportStereoCalibration(files, options, &c, &error)) << error;
  RectifiedPair pair;
  EXPECT_TRUE(RectifyCalibration(c, &pair, &error)) << error;
  return pair;
}

void ExpectSamePair(const RectifiedPair& a, const RectifiedPair& b, const std::string& what) {
  EXPECT_EQ(a.width, b.width) << what;
  EXPECT_NEAR(a.camera.fx, b.camera.fx, 1e-6) << what;
  EXPECT_NEAR(a.camera.fy, b.camera.fy, 1e-6) << what;
  EXPECT_NEAR(a.camera.cx, b.camera.cx, 1e-6) << what;
  EXPECT_NEAR(a.camera.cy, b.camera.cy, 1e-6) << what;
  EXPECT_NEAR(a.camera.baseline_m, b.camera.baseline_m, 1e-9) << what;
  EXPECT_LT((a.body_T_rectified.R - b.body_T_rectified.R).norm(), 1e-9) << what;
  EXPECT_LT((a.body_T_rectified.t - b.body_T_rectified.t).norm(), 1e-9) << what;
}

TEST(CalibrationImport, ReadsTheRealEurocSensorYamlAsTheFlightReaderDoes) {
  const std::string cam = SharedData() + "euroc-v101/mav0/cam";
  StereoCalibration c;
  std::string error;
  ASSERT_TRUE(
      ImportStereoCalibration({cam + "0/sensor.yaml", cam + "1/sensor.yaml"}, {}, &c, &error))
      << error;
  EXPECT_EQ(c.format, CalibrationFormat::kEuroc);
  frontend::CameraCalibration flight;
  ASSERT_TRUE(image_io::LoadCalibration(cam + "1/sensor.yaml", &flight, &error)) << error;
  EXPECT_EQ(c.right.width, 752);
  EXPECT_DOUBLE_EQ(c.right.fx, flight.fx);
  EXPECT_DOUBLE_EQ(c.right.k1, flight.k1);
  EXPECT_DOUBLE_EQ(c.right.p2, flight.p2);
  EXPECT_EQ(c.right.body_T_camera.Matrix(), flight.body_T_camera.Matrix());
  RectifiedPair pair;
  ASSERT_TRUE(RectifyCalibration(c, &pair, &error)) << error;
  EXPECT_NEAR(pair.camera.baseline_m, 0.110, 0.001);  // the VI-sensor's 11 cm
}

TEST(CalibrationImport, ReadsTheRealKittiCalibTxt) {
  ImportOptions o;
  o.width = 1226;
  o.height = 370;
  const RectifiedPair pair = Rectified({SharedData() + "kitti-odometry-excerpt/calib.txt"}, o);
  EXPECT_NEAR(pair.camera.fx, 707.0912, 1e-3);
  EXPECT_NEAR(pair.camera.baseline_m, 0.537, 0.001);
}

TEST(CalibrationImport, DetectsEveryFormat) {
  const std::string d = DataDir();
  const std::vector<std::pair<std::vector<std::string>, CalibrationFormat>> cases = {
      {{d + "euroc_left.yaml", d + "euroc_right.yaml"}, CalibrationFormat::kEuroc},
      {{d + "ros_left.yaml", d + "ros_right.yaml"}, CalibrationFormat::kRos},
      {{d + "kalibr_camchain.yaml"}, CalibrationFormat::kKalibr},
      {{d + "opencv_stereo.yaml"}, CalibrationFormat::kOpenCv},
      {{d + "kitti_calib.txt"}, CalibrationFormat::kKitti},
      {{d + "left.cahvor", d + "right.cahvor"}, CalibrationFormat::kCahvor},
  };
  for (const auto& [files, expected] : cases) {
    CalibrationFormat found = CalibrationFormat::kAuto;
    std::string error;
    EXPECT_TRUE(DetectFormat(files, &found, &error)) << error;
    EXPECT_EQ(found, expected) << files[0];
  }
}

// GIVEN one rig (fx 458, fy 457, k1 -0.28, k2 0.074, 0.11 m baseline) written by hand in five
// formats THEN every import gives the same rectified pair.
TEST(CalibrationImport, OneRigInFiveFormatsGivesOneRectifiedPair) {
  const std::string d = DataDir();
  const RectifiedPair euroc = Rectified({d + "euroc_left.yaml", d + "euroc_right.yaml"});
  EXPECT_NEAR(euroc.camera.baseline_m, 0.11, 1e-12);
  ExpectSamePair(euroc, Rectified({d + "kalibr_camchain.yaml"}), "kalibr");
  ExpectSamePair(euroc, Rectified({d + "opencv_stereo.yaml"}), "opencv");
  ExpectSamePair(euroc, Rectified({d + "ros_left.yaml", d + "ros_right.yaml"}), "ros");
  ExpectSamePair(euroc, Rectified({d + "left.cahvor", d + "right.cahvor"}), "cahvor");
}

TEST(CalibrationImport, CahvorLinearizesExactlyWhenTheDistortionAxisIsTheOpticalAxis) {
  const std::string d = DataDir();
  StereoCalibration c;
  std::string error;
  ASSERT_TRUE(ImportStereoCalibration({d + "left.cahvor", d + "right.cahvor"}, {}, &c, &error))
      << error;
  EXPECT_LT(c.linearization_error_px, 1e-6);
  EXPECT_NEAR(c.left.fx, 458.0, 1e-6);
  EXPECT_NEAR(c.left.k1, -0.28, 1e-6);
  EXPECT_NEAR(c.left.k2, 0.074, 1e-6);
  EXPECT_NEAR(c.left.k3, 0.0, 1e-6);
  // A perspective CAHVORE without pupil movement is the same camera.
  StereoCalibration e;
  ASSERT_TRUE(
      ImportStereoCalibration({d + "left_perspective.cahvore", d + "right.cahvor"}, {}, &e, &error))
      << error;
  EXPECT_NEAR(e.left.fx, c.left.fx, 1e-9);
  EXPECT_NEAR(e.left.k1, c.left.k1, 1e-9);
}

TEST(CalibrationImport, CahvorWithTheAxisOffIsLinearizedWithinItsReportedError) {
  const std::string d = DataDir();
  std::string text = ReadText(d + "left.cahvor");
  text.replace(text.find("O = 0.0 0.0 1.0"), 15, "O = 0.001 0.0005 1.0");
  const std::string left = WriteTemp("tilted.cahvor", text);
  StereoCalibration c;
  std::string error;
  ASSERT_TRUE(ImportStereoCalibration({left, d + "right.cahvor"}, {}, &c, &error)) << error;
  EXPECT_GT(c.linearization_error_px, 1e-4);
  EXPECT_LT(c.linearization_error_px, 0.5);
}

// The real EuRoC rig written as a ROS camera_info pair (rectification rotations and projections
// from the rectifier) imports to the same rectified pair, seen from the left camera.
TEST(CalibrationImport, RealEurocRigAsRosCameraInfoGivesTheSameRectifiedPair) {
  const std::string cam = SharedData() + "euroc-v101/mav0/cam";
  StereoCalibration euroc;
  std::string error;
  ASSERT_TRUE(
      ImportStereoCalibration({cam + "0/sensor.yaml", cam + "1/sensor.yaml"}, {}, &euroc, &error));
  RectifiedPair pair;
  ASSERT_TRUE(RectifyCalibration(euroc, &pair, &error)) << error;
  const Eigen::Matrix3d rect_R_body = pair.body_T_rectified.R.transpose();
  const auto camera_info = [&](const frontend::CameraCalibration& c, double tx) {
    const Eigen::Matrix3d r = rect_R_body * c.body_T_camera.R;
    std::ostringstream s;
    s.precision(17);
    s << "image_width: " << c.width << "\nimage_height: " << c.height
      << "\ncamera_matrix: {rows: 3, cols: 3, data: [" << c.fx << ", 0, " << c.cx << ", 0, " << c.fy
      << ", " << c.cy << ", 0, 0, 1]}\ndistortion_model: plumb_bob\n"
      << "distortion_coefficients: {rows: 1, cols: 5, data: [" << c.k1 << ", " << c.k2 << ", "
      << c.p1 << ", " << c.p2 << ", " << c.k3 << "]}\nrectification_matrix: {rows: 3, cols: 3, "
      << "data: [";
    for (int i = 0; i < 9; ++i) s << (i ? ", " : "") << r(i / 3, i % 3);
    s << "]}\nprojection_matrix: {rows: 3, cols: 4, data: [" << pair.camera.fx << ", 0, "
      << pair.camera.cx << ", " << tx << ", 0, " << pair.camera.fy << ", " << pair.camera.cy
      << ", 0, 0, 0, 1, 0]}\n";
    return s.str();
  };
  const std::string left = WriteTemp("euroc_left_info.yaml", camera_info(euroc.left, 0.0));
  const std::string right = WriteTemp(
      "euroc_right_info.yaml", camera_info(euroc.right, -pair.camera.fx * pair.camera.baseline_m));
  RectifiedPair ros = Rectified({left, right});
  RectifiedPair expected = pair;
  expected.body_T_rectified = euroc.left.body_T_camera.Inverse() * pair.body_T_rectified;
  ExpectSamePair(expected, ros, "ros from euroc");
}

TEST(CalibrationImport, WrittenEurocYamlReadsBackToTheSameCameras) {
  const std::string cam = SharedData() + "euroc-v101/mav0/cam";
  StereoCalibration c;
  std::string error;
  ASSERT_TRUE(
      ImportStereoCalibration({cam + "0/sensor.yaml", cam + "1/sensor.yaml"}, {}, &c, &error));
  const std::string left = WriteTemp("w_left.yaml", EurocSensorYaml(c.left));
  const std::string right = WriteTemp("w_right.yaml", EurocSensorYaml(c.right));
  StereoCalibration back;
  ASSERT_TRUE(ImportStereoCalibration({left, right}, {}, &back, &error)) << error;
  EXPECT_EQ(back.right.fx, c.right.fx);
  EXPECT_EQ(back.right.k2, c.right.k2);
  EXPECT_EQ(back.right.body_T_camera.Matrix(), c.right.body_T_camera.Matrix());
  frontend::CameraCalibration flight;  // the flight reader takes the written file too
  ASSERT_TRUE(image_io::LoadCalibration(right, &flight, &error)) << error;
  EXPECT_EQ(flight.fx, c.right.fx);
}

struct Malformed {
  const char* name;    // the good file the case starts from
  const char* from;    // text replaced ...
  const char* to;      // ... by this
  const char* expect;  // in the error
};

// One test per malformed case: the good file with one edit, imported with its partner file
// unchanged; the refusal names the edited file and says what is wrong.
class MalformedFile : public ::testing::TestWithParam<Malformed> {};

TEST_P(MalformedFile, IsRefusedNamingFileAndKey) {
  const Malformed& m = GetParam();
  const std::string d = DataDir();
  const std::map<std::string, std::string> partner = {{"euroc_left.yaml", "euroc_right.yaml"},
                                                      {"ros_left.yaml", "ros_right.yaml"},
                                                      {"left.cahvor", "right.cahvor"}};
  std::string text = ReadText(d + m.name);
  const std::size_t at = text.find(m.from);
  ASSERT_NE(at, std::string::npos) << m.from;
  text.replace(at, std::string(m.from).size(), m.to);
  const std::string path = WriteTemp(std::string("bad_") + m.name, text);
  std::vector<std::string> files = {path};
  if (partner.count(m.name) != 0) files.push_back(d + partner.at(m.name));
  ImportOptions options;
  if (std::string(m.name) == "kitti_calib.txt") {
    options.format = CalibrationFormat::kKitti;
    options.width = 1242;
    options.height = 375;
  }
  StereoCalibration c;
  std::string error;
  EXPECT_FALSE(ImportStereoCalibration(files, options, &c, &error)) << m.expect;
  EXPECT_NE(error.find(m.expect), std::string::npos)
      << "expected '" << m.expect << "' in: " << error;
  EXPECT_NE(error.find(path), std::string::npos) << error;
}

const Malformed kMalformedCases[] = {
    {"euroc_left.yaml", "intrinsics: [458.0, ", "intrinsics: [",
     "intrinsics: needs 4 numbers, has 3"},
    {"euroc_left.yaml", "resolution: [752, 480]\n", "", "resolution: missing"},
    {"euroc_left.yaml", "camera_model: pinhole", "camera_model: omni",
     "camera_model: 'omni' is not supported"},
    {"euroc_left.yaml", "0.0, 0.0, 0.0, 1.0]", "0.0, 0.0, 1.0, 1.0]", "T_BS: the last row"},
    {"euroc_left.yaml", "[1.0, 0.0, 0.0, 0.0,", "[2.0, 0.0, 0.0, 0.0,",
     "T_BS: the 3x3 block is not a rotation"},
    {"euroc_left.yaml", "-0.28,", "abc,", "distortion_coefficients: is not a list of numbers"},
    {"euroc_left.yaml", "-0.28,", ".nan,", "non-finite"},
    {"euroc_left.yaml", "resolution: [752, 480]", "resolution: [752, 480", "not valid YAML"},
    {"euroc_left.yaml", "intrinsics: [458.0, 457.0", "intrinsics: [-458.0, 457.0",
     "focal lengths must be positive"},
    {"ros_left.yaml", "image_width: 752\n", "", "image_width: missing"},
    {"ros_left.yaml", "distortion_model: plumb_bob", "distortion_model: equidistant",
     "'equidistant' is not supported"},
    {"ros_left.yaml", "rows: 3\n  cols: 4", "rows: 3\n  cols: 3",
     "rows x cols = 9 but data holds 12"},
    {"ros_left.yaml", "data: [458.0, 0.0, 367.0", "data: [458.0, 1.0, 367.0",
     "skew is not supported"},
    {"kalibr_camchain.yaml", "distortion_model: radtan\n  intrinsics",
     "distortion_model: equidistant\n  intrinsics",
     "distortion_model: 'equidistant' is not supported"},
    {"kalibr_camchain.yaml", "  - [1.0, 0.0, 0.0, -0.11]", "  - [1.0, 0.0, 0.0]",
     "T_cn_cnm1: needs 16 numbers, has 15"},
    {"kalibr_camchain.yaml", "cam1:", "camX:", "cam1: missing"},
    {"kalibr_camchain.yaml", "-0.11]", "0.0]", "cannot rectify"},
    {"opencv_stereo.yaml", "image_width: 752\nimage_height: 480\n", "", "no image size"},
    {"opencv_stereo.yaml", "data: [ -0.11, 0., 0. ]", "data: [ -0.11, 0. ]",
     "rows x cols = 3 but data holds 2"},
    {"opencv_stereo.yaml", "T: !!opencv-matrix", "Q: !!opencv-matrix", "T: missing"},
    {"kitti_calib.txt", "P1: 7.070912e+02 0.000000e+00 ", "P1: 7.070912e+02 ",
     "P1: needs 12 finite numbers, has 11"},
    {"kitti_calib.txt", "P1:", "P2:", "P1: missing"},
    {"left.cahvor", "H = 458.0 0.0 367.0\n", "", "H: missing"},
    {"left.cahvor", "A = 0.0 0.0 1.0", "A = 0.0 0.0 x", ":5: A: needs 3 finite numbers, has text"},
    {"left.cahvor", "R = 0.0 -0.28 0.074\n", "", "CAHVOR needs both O and R"},
    {"left.cahvor", "C = 0.0 0.0 0.0\n", "C = 0.0 0.0 0.0\nC = 0.0 0.0 0.0\n", "C: given twice"}};

INSTANTIATE_TEST_SUITE_P(EveryFormat, MalformedFile, ::testing::ValuesIn(kMalformedCases));

TEST(CalibrationImport, RefusesWhatNoFormatReads) {
  const std::string d = DataDir();
  StereoCalibration c;
  std::string error;
  EXPECT_FALSE(ImportStereoCalibration({"/nonexistent/cam.yaml"}, {}, &c, &error));
  EXPECT_NE(error.find("/nonexistent/cam.yaml: cannot open"), std::string::npos) << error;
  EXPECT_FALSE(ImportStereoCalibration({d + "euroc_left.yaml"}, {}, &c, &error));
  EXPECT_NE(error.find("needs 2 files"), std::string::npos) << error;
  const std::string junk = WriteTemp("junk.yaml", "hello: world\n");
  EXPECT_FALSE(ImportStereoCalibration({junk}, {}, &c, &error));
  EXPECT_NE(error.find("not a calibration format"), std::string::npos) << error;
  EXPECT_FALSE(ImportStereoCalibration({d + "kitti_calib.txt"}, {}, &c, &error));
  EXPECT_NE(error.find("no image size"), std::string::npos) << error;
  EXPECT_FALSE(
      ImportStereoCalibration({d + "fisheye.cahvore", d + "right.cahvor"}, {}, &c, &error));
  EXPECT_NE(error.find("fisheye"), std::string::npos) << error;
  EXPECT_FALSE(ImportStereoCalibration({WriteTemp("empty.yaml", "")}, {}, &c, &error));
}

}  // namespace
}  // namespace swf::calibration
