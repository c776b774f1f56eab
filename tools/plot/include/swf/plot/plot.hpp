// The pictures of a descent, for a reader who was not there: each plot has a title, axes with
// units, a legend or colour key, and a scale bar where it is a map. One module draws them for
// every tool that shows a run (swf-sil's summary.plot_dir in the demo, swf-plot on the logs of a
// replay or of a campaign's runs, swf-hazard, swf-sim), so the same run looks the same whichever
// tool drew it.
//
// Drawn by gnuplot (Debian's gnuplot-nox, pngcairo terminal): each call writes its data and
// script into a fresh temporary directory, runs gnuplot there, checks its exit status and that it
// produced a PNG, and only then copies the PNG to its destination (a failed plot leaves no
// half-written file). The program is `gnuplot` on PATH, or what SWF_GNUPLOT names.
//
// Every Draw* returns true when the PNG was written, or false with `error` naming the PNG and the
// cause ("out/map.png: gnuplot exited with status 1: line 7: ..."): never a silent skip. Times
// are seconds since the run's first navigation output; positions are world metres (z up).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "swf/evaluation/hazard_score.hpp"
#include "swf/evaluation/run_judge.hpp"

namespace swf::plot {

// The program Draw* runs: $SWF_GNUPLOT when set and not empty, else "gnuplot".
std::string GnuplotProgram();

// --- A judged run (evaluation::RunScore: swf-sil live, swf-plot from logs) ----------------

// trajectory.png: height z, x and y of the estimate against truth (the truth drawn wide and
// light beneath the estimate, so neither hides the other), and the position error per world axis
// with the output's own +-3 sigma band (from nav_state_t.covariance; a gap where the output had
// none), against time.
bool DrawTrajectory(const evaluation::RunScore& score, const std::string& png, std::string* error);
// attitude_error.png: the rotation error about each camera axis (Log(est_R^T true_R), degrees)
// with the output's +-3 sigma band, and the total angle, against time.
bool DrawAttitudeError(const evaluation::RunScore& score, const std::string& png,
                       std::string* error);
// landmark_error.png: RMS and median error of each published landmark map against time (log
// scale), and how many landmarks each judged.
bool DrawLandmarkError(const evaluation::RunScore& score, const std::string& png,
                       std::string* error);
// map.png: the last judged landmark map seen from above: true positions as open circles, the
// estimates coloured by their error (colour key in metres, up to the 95th percentile when a few
// outliers would flatten it; those beyond are drawn as triangles with their own legend entry).
bool DrawLandmarkMap(const evaluation::RunScore& score, const std::string& png, std::string* error);

// --- Maps on a grid ------------------------------------------------------------------------

// A published hazard map (hazard_map_t) seen from above, two panels: the elevation with its
// colour key (m; unknown cells left blank), and the hazard class per cell with a colour key of
// class names; the chosen safe site marked on both with the lander footprint (radius in metres;
// <= 0 draws the site without it). `title` heads the figure.
bool DrawHazardMap(const evaluation::HazardMapView& map, double footprint_radius_m,
                   const std::string& title, const std::string& png, std::string* error);

// A height field on a square grid: node (i, j) at (x0 + i cell_m, y0 + j cell_m), row-major.
struct HeightGrid {
  double x0_m = 0.0;
  double y0_m = 0.0;
  double cell_m = 0.0;
  int size = 0;
  std::vector<float> height_m;
  // Per node, the simulator's hazard truth bits (sim::HazardBits: 1 slope, 2 rock).
  std::vector<std::uint8_t> hazard_bits;
};
// The terrain and its hazard truth: height with its colour key (m), and the truth classes (safe,
// too steep, rock) with their key, the descent's target marked when `target_valid`.
bool DrawTerrainHazard(const HeightGrid& terrain, bool target_valid, const double target_m[2],
                       const std::string& title, const std::string& png, std::string* error);

// --- Images --------------------------------------------------------------------------------

struct ContactFrame {
  std::int64_t frame = 0;
  double altitude_m = 0.0;  // true height above the terrain below
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> gray;  // row-major, top row first
};
// Frames side by side (up to 4 a row), each labelled with its frame number and altitude.
bool DrawContactSheet(const std::vector<ContactFrame>& frames, const std::string& title,
                      const std::string& png, std::string* error);

// --- Curves --------------------------------------------------------------------------------

struct Series {
  std::string title;
  std::vector<double> x;
  std::vector<double> y;  // NaN: no value (a gap)
};
struct LineChart {
  std::string title;
  std::string x_label;  // with its unit, "altitude (m)"
  std::string y_label;
  bool log_y = false;
  std::vector<Series> series;
};
// Lines with points, the legend outside the plot on the right.
bool DrawLineChart(const LineChart& chart, const std::string& png, std::string* error);

// A line chart whose series share one x, as a text file that says everything the plot needs
// (swf-eval's OUT/NAME.dat; `swf-plot curves` draws it). Every header line starts with '#', so
// gnuplot reads the rows as they are:
//   # title: Fig. 13: landmark error on the descent
//   # x: frame number
//   # y: landmark mean squared error (m^2)
//   # y scale: log                          ("linear" or "log")
//   # series: "batch" "SWF(3)" "CRLB"
//   1 0.0123 0.0131 0.0101                  x, then one value per series (NaN: no value)
// Write: false with `error` naming the file when the series do not share the first one's x, a
// title holds a '"' or a line break, or the file cannot be written.
bool WriteLineChart(const LineChart& chart, const std::string& path, std::string* error);
// Read: false with `error` naming the file and, where it is one line's fault, the line
// ("out/eval/fig13_descent.dat:7: expected 9 numbers (x and 8 series), found 8").
bool ReadLineChart(const std::string& path, LineChart* chart, std::string* error);

// --- All of a run --------------------------------------------------------------------------

// What DrawRun draws beside the score: the last published hazard map (null: none).
struct RunPictures {
  const evaluation::HazardMapView* last_hazard_map = nullptr;
  double footprint_radius_m = 0.0;
};
// trajectory.png, attitude_error.png, landmark_error.png, map.png and hazard.png into `dir`, each
// when the run has what it shows (outputs, maps, a hazard map). Returns the PNGs written; every
// failure is appended to `errors`.
std::vector<std::string> DrawRun(const evaluation::RunScore& score, const RunPictures& pictures,
                                 const std::string& dir, std::vector<std::string>* errors);

}  // namespace swf::plot
