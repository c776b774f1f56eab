// Every plot of swf::plot drawn from small inputs built here, checked as an image (png_check.hpp),
// and every way a plot can fail reported with the PNG and the cause: gnuplot missing, gnuplot
// failing, an unwritable destination, nothing to draw.
#include "swf/plot/plot.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "png_check.hpp"
#include "swf_msgs/hazard_map_t.hpp"

namespace swf::plot {
namespace {

class PlotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("swf_plot_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    ::unsetenv("SWF_GNUPLOT");
  }
  void TearDown() override {
    std::filesystem::remove_all(dir_);
    ::unsetenv("SWF_GNUPLOT");
  }
  std::string Png(const std::string& name) const { return (dir_ / name).string(); }

  // A drawn plot: decodes, has the canvas's size, is not blank.
  static void ExpectPlot(const std::string& path, int width, int height) {
    const test::PngStats s = test::StatsOf(path);
    ASSERT_TRUE(s.decoded) << s.error;
    EXPECT_EQ(s.width, width);
    EXPECT_EQ(s.height, height);
    EXPECT_GT(s.gray_stddev, 5.0) << path << " looks blank";
  }

  std::filesystem::path dir_;
};

// GIVEN a descent of 40 outputs at 10 Hz whose error grows inside a growing covariance, and
// landmark maps every 5 outputs with a few far-off landmarks.
evaluation::RunScore Descent() {
  evaluation::RunScore score;
  for (int k = 0; k < 40; ++k) {
    evaluation::OutputScore o;
    o.frame_seq = k;
    o.utime = 5'000'000 + k * 100'000;
    for (int i = 0; i < 3; ++i) {
      o.truth_m[i] = i == 2 ? 100.0 - 2.0 * k : 0.1 * i;
      o.estimate_m[i] = o.truth_m[i] + 0.01 * std::sin(0.3 * k + i) * (1 + 0.1 * k);
      o.position_sigma_m[i] = k < 3 ? NAN : 0.01 * (1 + 0.1 * k);  // none at first
      o.attitude_error_axes_deg[i] = 0.02 * std::cos(0.2 * k + i);
      o.attitude_sigma_deg[i] = 0.02 + 0.001 * k;
    }
    o.attitude_error_deg = 0.03;
    score.outputs.push_back(o);
  }
  for (int m = 0; m < 8; ++m) {
    score.maps.push_back({5 * m, 5'000'000 + 500'000 * m, 50, 0.2 / (m + 1), 0.15 / (m + 1)});
  }
  for (int l = 0; l < 60; ++l) {
    evaluation::LandmarkScore s;
    s.id = l;
    s.truth_m[0] = (l % 10) - 5.0;
    s.truth_m[1] = std::floor(l / 10.0) - 3.0;      // rows of 10
    const double e = l < 3 ? 1.0 : 0.01 * (l % 7);  // three outliers beyond the colour key
    s.estimate_m[0] = s.truth_m[0] + e;
    s.estimate_m[1] = s.truth_m[1];
    s.error_m = e;
    score.last_map.push_back(s);
  }
  return score;
}

TEST_F(PlotTest, DrawsEveryPlotOfARun) {
  const evaluation::RunScore score = Descent();
  std::string error;
  ASSERT_TRUE(DrawTrajectory(score, Png("trajectory.png"), &error)) << error;
  ExpectPlot(Png("trajectory.png"), 1300, 950);
  ASSERT_TRUE(DrawAttitudeError(score, Png("attitude.png"), &error)) << error;
  ExpectPlot(Png("attitude.png"), 1100, 800);
  ASSERT_TRUE(DrawLandmarkError(score, Png("landmark_error.png"), &error)) << error;
  ExpectPlot(Png("landmark_error.png"), 1000, 600);
  ASSERT_TRUE(DrawLandmarkMap(score, Png("map.png"), &error)) << error;
  ExpectPlot(Png("map.png"), 900, 950);
}

TEST_F(PlotTest, DrawsAHazardMapWithUnknownCellsAndItsSite) {
  constexpr int kSide = 40;
  std::vector<float> elevation(kSide * kSide), sigma(kSide * kSide, 0.05f);
  std::vector<std::int8_t> classes(kSide * kSide);
  for (int c = 0; c < kSide * kSide; ++c) {
    const int i = c % kSide, j = c / kSide;
    elevation[c] = i < 4 ? NAN : 0.02f * static_cast<float>(i + j);
    classes[c] =
        static_cast<std::int8_t>(i < 4 ? swf_msgs::hazard_map_t::CLASS_UNKNOWN : (i * j) % 6);
  }
  evaluation::HazardMapView map;
  map.frame_seq = 9;
  map.origin_world_m[0] = -2.0;
  map.origin_world_m[1] = -2.0;
  map.cell_m = 0.1;
  map.cells_per_side = kSide;
  map.elevation_m = elevation.data();
  map.sigma_m = sigma.data();
  map.hazard_class = classes.data();
  map.site_valid = true;
  map.site_world_m[0] = 0.5;
  map.site_world_m[1] = 0.2;
  map.site_score = 0.7;
  std::string error;
  ASSERT_TRUE(DrawHazardMap(map, 0.5, "hazard at frame 9", Png("hazard.png"), &error)) << error;
  ExpectPlot(Png("hazard.png"), 1240, 680);
}

TEST_F(PlotTest, DrawsTerrainWithHazardTruthReducedToBlocks) {
  HeightGrid terrain;
  terrain.size = 700;  // more than 300 a side: drawn as 3x3 blocks
  terrain.cell_m = 0.1;
  terrain.x0_m = terrain.y0_m = -35.0;
  terrain.height_m.resize(700 * 700);
  terrain.hazard_bits.resize(700 * 700);
  for (std::size_t c = 0; c < terrain.height_m.size(); ++c) {
    terrain.height_m[c] = static_cast<float>(std::sin(0.01 * static_cast<double>(c % 700)));
    terrain.hazard_bits[c] = c % 997 == 0 ? 2 : (c % 700 < 50 ? 1 : 0);
  }
  const double target[2] = {1.0, 2.0};
  std::string error;
  ASSERT_TRUE(DrawTerrainHazard(terrain, true, target, "terrain", Png("terrain.png"), &error))
      << error;
  ExpectPlot(Png("terrain.png"), 1240, 680);
}

TEST_F(PlotTest, DrawsAContactSheetAndALineChart) {
  std::vector<ContactFrame> frames;
  for (int k = 0; k < 6; ++k) {
    ContactFrame f{k * 10, 100.0 - 10 * k, 64, 48, std::vector<std::uint8_t>(64 * 48)};
    for (std::size_t p = 0; p < f.gray.size(); ++p) f.gray[p] = static_cast<std::uint8_t>(p * 7);
    frames.push_back(f);
  }
  std::string error;
  ASSERT_TRUE(DrawContactSheet(frames, "sheet", Png("sheet.png"), &error)) << error;
  ExpectPlot(Png("sheet.png"), 4 * 320, 2 * (320 * 48 / 64 + 40) + 50);
  LineChart chart{"chart",
                  "altitude (m)",
                  "rate",
                  true,
                  {{"a", {10, 20, 30}, {0.1, 0.0, 0.3}}, {"b", {10, 20, 30}, {1, 2, NAN}}}};
  ASSERT_TRUE(DrawLineChart(chart, Png("chart.png"), &error)) << error;
  ExpectPlot(Png("chart.png"), 1000, 600);
}

// Whether any pixel of the outermost `columns` columns on either side is dark (text or lines):
// a title wider than the canvas is cut there, while a plot keeps its margins clear.
bool DarkAtTheSideEdges(const std::string& path, int columns) {
  image_io::GrayImage image;
  std::string error;
  EXPECT_TRUE(image_io::LoadGray(path, &image, &error)) << error;
  for (int y = 0; y < image.height; ++y) {
    for (int k = 0; k < columns; ++k) {
      const std::size_t row = static_cast<std::size_t>(y) * image.width;
      if (image.pixels[row + k] < 128 || image.pixels[row + image.width - 1 - k] < 128) return true;
    }
  }
  return false;
}

// GIVEN titles far wider than their canvas (a line chart's, and a one-frame contact sheet's,
// 320 px wide): each is broken into lines that fit, so nothing is cut at the image's edges, and
// quotes and backslashes in it reach gnuplot as text.
TEST_F(PlotTest, LongTitlesAreBrokenIntoLinesNotCutAtTheEdges) {
  std::string title = "Fig. 99, \"image level\": a\\b";
  while (title.size() < 220) title += " landmark error of the maps against the renderer's truth";
  LineChart chart{title, "frame", "error (m)", false, {{"a", {1, 2, 3}, {0.3, 0.2, 0.1}}}};
  std::string error;
  ASSERT_TRUE(DrawLineChart(chart, Png("chart.png"), &error)) << error;
  ExpectPlot(Png("chart.png"), 1000, 600);
  EXPECT_FALSE(DarkAtTheSideEdges(Png("chart.png"), 3));

  ContactFrame frame{0, 100.0, 64, 48, std::vector<std::uint8_t>(64 * 48, 200)};  // light
  ASSERT_TRUE(DrawContactSheet({frame},
                               "Left camera, scenario 'descent' over terrain 'rocks', "
                               "a_single_word_longer_than_the_whole_line_of_the_title",
                               Png("sheet.png"), &error))
      << error;
  EXPECT_FALSE(DarkAtTheSideEdges(Png("sheet.png"), 3));
}

// GIVEN a chart of two series over one x, with a gap: written as text, read back the same and
// drawn; what the file cannot hold is refused when writing.
TEST_F(PlotTest, LineChartFileRoundTripsAndIsDrawn) {
  const LineChart chart{
      "Fig. 1: error: growing",
      "frame number",
      "position error (m)",
      true,
      {{"SWF(5)", {1, 2, 3}, {0.5, NAN, 0.125}}, {"1/m", {1, 2, 3}, {1, 0.5, 1e-7}}}};
  std::string error;
  ASSERT_TRUE(WriteLineChart(chart, Png("chart.dat"), &error)) << error;
  LineChart read;
  ASSERT_TRUE(ReadLineChart(Png("chart.dat"), &read, &error)) << error;
  EXPECT_EQ(read.title, chart.title);
  EXPECT_EQ(read.x_label, chart.x_label);
  EXPECT_EQ(read.y_label, chart.y_label);
  EXPECT_TRUE(read.log_y);
  ASSERT_EQ(read.series.size(), 2u);
  EXPECT_EQ(read.series[1].title, "1/m");
  EXPECT_EQ(read.series[1].x, chart.series[1].x);
  EXPECT_EQ(read.series[1].y, chart.series[1].y);
  EXPECT_TRUE(std::isnan(read.series[0].y[1]));
  ASSERT_TRUE(DrawLineChart(read, Png("chart.png"), &error)) << error;
  ExpectPlot(Png("chart.png"), 1000, 600);

  LineChart unshared = chart;
  unshared.series[1].x = {1, 2, 4};
  EXPECT_FALSE(WriteLineChart(unshared, Png("u.dat"), &error));
  EXPECT_NE(error.find("series '1/m' does not share the x of 'SWF(5)'"), std::string::npos)
      << error;
  LineChart quoted = chart;
  quoted.series[0].title = "say \"hi\"";
  EXPECT_FALSE(WriteLineChart(quoted, Png("q.dat"), &error));
  EXPECT_EQ(error.rfind(Png("q.dat") + ": series name", 0), 0u) << error;
}

// GIVEN files that each break one rule: the error names the file, the line where it is one
// line's fault, and what is wrong.
TEST_F(PlotTest, MalformedLineChartFilesAreNamedWithTheirLine) {
  const std::string header =
      "# title: t\n# x: frame number\n# y: error (m)\n# y scale: linear\n# series: \"a\"\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {header + "1 2\n# title: again\n", ":7: a header line after the data rows"},
      {"# title: t\n# title: u\n", ":2: a second 'title' line"},
      {"# title: t\n# y scale: cubic\n", ":2: y scale 'cubic': expected log or linear"},
      {"# series: a b\n", ":1: series: expected quoted names"},
      {"# colour: red\n", ":1: unknown header 'colour'"},
      {"1 2\n", ":1: a data row before the '# series:' line"},
      {header + "inf 2\n", ":6: column 1: 'inf' is not finite"},
      {header + "nan 2\n", ":6: column 1: 'nan' is not finite"},
      {header, ": no data rows"},
      {"# title: t\n# x: f\n# y scale: log\n# series: \"a\"\n1 2\n",
       ": the header has no '# y:' line"},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const std::string path = Png("bad" + std::to_string(k) + ".dat");
    {
      std::ofstream out(path);
      out << cases[k].first;
    }
    LineChart chart;
    std::string error;
    EXPECT_FALSE(ReadLineChart(path, &chart, &error)) << cases[k].first;
    EXPECT_EQ(error.rfind(path + cases[k].second, 0), 0u) << error;
  }
  LineChart chart;
  std::string error;
  EXPECT_FALSE(ReadLineChart(Png("none.dat"), &chart, &error));
  EXPECT_EQ(error.rfind(Png("none.dat") + ": cannot read: ", 0), 0u) << error;
}

// GIVEN a gnuplot that cannot be started, one that fails and one that succeeds without drawing
// WHEN a run's plots are drawn THEN each fails naming the PNG and the cause, and leaves no PNG.
TEST_F(PlotTest, GnuplotThatDrawsNothingIsNamed) {
  const std::pair<const char*, std::string> cases[] = {
      {"/nonexistent/gnuplot", "cannot run /nonexistent/gnuplot: "},
      {"false", "false exited with status 1"},
      {"true", "true exited with status 0 but drew no image"}};
  using Draw = bool (*)(const evaluation::RunScore&, const std::string&, std::string*);
  for (const auto& [gnuplot, cause] : cases) {
    ::setenv("SWF_GNUPLOT", gnuplot, 1);
    for (const Draw draw : {&DrawTrajectory, &DrawLandmarkMap}) {
      const std::string png = Png("plot.png");
      std::string error;
      EXPECT_FALSE(draw(Descent(), png, &error)) << gnuplot;
      EXPECT_EQ(error.rfind(png + ": " + cause, 0), 0u) << error;
      EXPECT_FALSE(std::filesystem::exists(png)) << gnuplot;
    }
  }
}

TEST_F(PlotTest, UnwritableDestinationAndEmptyRunsAreNamed) {
  std::string error;
  EXPECT_FALSE(DrawLandmarkError(Descent(), Png("no/such/dir/e.png"), &error));
  EXPECT_NE(error.find("no/such/dir/e.png: cannot write the PNG"), std::string::npos) << error;
  const evaluation::RunScore empty;
  EXPECT_FALSE(DrawTrajectory(empty, Png("t.png"), &error));
  EXPECT_NE(error.find("no navigation output"), std::string::npos) << error;
  std::vector<std::string> errors;
  EXPECT_TRUE(DrawRun(empty, {}, dir_.string(), &errors).empty());  // nothing to draw: no file
  EXPECT_TRUE(errors.empty());
}

}  // namespace
}  // namespace swf::plot
