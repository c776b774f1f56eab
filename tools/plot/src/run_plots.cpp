// The plots of a judged run: trajectory, attitude error, landmark error and the landmark map.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "gnuplot_job.hpp"
#include "style.hpp"
#include "swf/plot/plot.hpp"

namespace swf::plot {

namespace {

// Columns: 1 t, 2-4 estimate, 5-7 truth, 8-10 error (estimate - truth) per world axis, 11-13
// position sigma, 14-16 attitude error per camera axis (deg), 17-19 attitude sigma (deg),
// 20 attitude error angle (deg).
std::string OutputTable(const evaluation::RunScore& score) {
  const std::int64_t origin = TimeOriginUs(score);
  std::ostringstream out;
  for (const evaluation::OutputScore& o : score.outputs) {
    out << Number(Seconds(o.utime, origin));
    for (double v : o.estimate_m) out << ' ' << Number(v);
    for (double v : o.truth_m) out << ' ' << Number(v);
    for (int i = 0; i < 3; ++i) out << ' ' << Number(o.estimate_m[i] - o.truth_m[i]);
    for (double v : o.position_sigma_m) out << ' ' << Number(v);
    for (double v : o.attitude_error_axes_deg) out << ' ' << Number(v);
    for (double v : o.attitude_sigma_deg) out << ' ' << Number(v);
    out << ' ' << Number(o.attitude_error_deg) << '\n';
  }
  return out.str();
}

// One panel: a value against time with its +-3 sigma band around zero.
std::string ErrorPanel(const std::string& data, const std::string& y_label, int error_column,
                       int sigma_column, const std::string& error_title) {
  std::ostringstream s;
  s << "set ylabel '" << y_label << "'\n"
    << "plot " << data << " using 1:(-3*$" << sigma_column << "):(3*$" << sigma_column
    << ") with filledcurves " << kBandStyle << " title '±3σ of the output''s covariance', \\\n"
    << "  0 with lines lc rgb '#808080' notitle, \\\n"
    << "  " << data << " using 1:" << error_column << " with lines " << kEstimateStyle << " title '"
    << error_title << "'\n";
  return s.str();
}

// True (and *error says so) when the run has none of `what`: there is nothing to draw.
bool Missing(bool empty, const std::string& png, const char* what, std::string* error) {
  if (!empty) return false;
  *error = png + ": the run has no " + what + " to plot";
  return true;
}

}  // namespace

bool DrawTrajectory(const evaluation::RunScore& score, const std::string& png, std::string* error) {
  if (Missing(score.outputs.empty(), png, "navigation output with truth", error)) return false;
  GnuplotJob job(1300, 950);
  const std::string d = job.Data("outputs.dat", OutputTable(score));
  std::ostringstream s;
  s << Preamble() << "set key outside top center horizontal\n"
    << "set multiplot layout 3,2 rowsfirst title 'Descent trajectory: the estimate against truth ("
    << score.outputs.size() << " navigation outputs)' font ',13'\n";
  const char* axis[3] = {"x", "y", "z"};
  const int order[3] = {2, 0, 1};  // height first, then the horizontal track
  for (int row = 0; row < 3; ++row) {
    const int a = order[row];
    if (row == 2) s << "set xlabel '" << kTimeLabel << "'\n";
    s << "set ylabel '" << (a == 2 ? "height z" : std::string("horizontal ") + axis[a])
      << " (world, m)'\n"
      << "plot " << d << " using 1:" << 5 + a << " with lines " << kTruthStyle
      << " title 'truth', \\\n  " << d << " using 1:" << 2 + a << " with lines " << kEstimateStyle
      << " title 'estimate'\n";
    s << ErrorPanel(d, std::string("position error in ") + axis[a] + " (m)", 8 + a, 11 + a,
                    "estimate − truth");
  }
  s << "unset multiplot\n";
  return job.Render(s.str(), png, error);
}

bool DrawAttitudeError(const evaluation::RunScore& score, const std::string& png,
                       std::string* error) {
  if (Missing(score.outputs.empty(), png, "navigation output with truth", error)) return false;
  GnuplotJob job(1100, 800);
  const std::string d = job.Data("outputs.dat", OutputTable(score));
  std::ostringstream s;
  s << Preamble() << "set key outside top center horizontal\n"
    << "set multiplot layout 2,2 rowsfirst title 'Attitude error: Log(est_R^T true_R) about the "
       "estimate''s camera axes (x right, y down, z along the optical axis)' font ',12'\n";
  const char* axis[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (a >= 1) s << "set xlabel '" << kTimeLabel << "'\n";
    s << ErrorPanel(d, std::string("rotation about camera ") + axis[a] + " (deg)", 14 + a, 17 + a,
                    "error");
  }
  s << "set ylabel 'total rotation error (deg)'\n"
    << "plot " << d << " using 1:20 with lines " << kEstimateStyle
    << " title 'angle of est_R^T true_R'\n"
    << "unset multiplot\n";
  return job.Render(s.str(), png, error);
}

bool DrawLandmarkError(const evaluation::RunScore& score, const std::string& png,
                       std::string* error) {
  if (Missing(score.maps.empty(), png, "landmark map with truth", error)) return false;
  const std::int64_t origin = TimeOriginUs(score);
  std::ostringstream data;
  for (const evaluation::MapScore& m : score.maps) {
    data << Number(Seconds(m.utime, origin)) << ' ' << Number(m.rms_error_m) << ' '
         << Number(m.median_error_m) << ' ' << m.landmarks_evaluated << '\n';
  }
  GnuplotJob job(1000, 600);
  const std::string d = job.Data("maps.dat", data.str());
  std::ostringstream s;
  s << Preamble() << "set key outside top center horizontal\n"
    << "set title 'Landmark error against truth, each published landmark map (" << score.maps.size()
    << " maps)' font ',12'\n"
    << "set xlabel '" << kTimeLabel << "'\nset ylabel 'landmark position error (m)'\n"
    << "set logscale y\nset y2label 'landmarks judged'\nset y2tics\nset ytics nomirror\n"
    << "set y2range [0:*]\n"
    << "plot " << d << " using 1:4 axes x1y2 with steps lw 1 lc rgb '#a0a0a0' title "
    << "'landmarks judged (right axis)', \\\n  " << d
    << " using 1:2 with linespoints pt 7 ps 0.6 lw 1.5 lc rgb '#c0392b' title 'RMS', \\\n  " << d
    << " using 1:3 with linespoints pt 5 ps 0.6 lw 1.5 lc rgb '#2c7bb6' title 'median'\n";
  return job.Render(s.str(), png, error);
}

bool DrawLandmarkMap(const evaluation::RunScore& score, const std::string& png,
                     std::string* error) {
  if (Missing(score.last_map.empty(), png, "judged landmark map", error)) return false;
  std::vector<double> errors;
  double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
  for (const evaluation::LandmarkScore& l : score.last_map) {
    errors.push_back(l.error_m);
    for (const double* p : {l.estimate_m, l.truth_m}) {
      x_lo = std::min(x_lo, p[0]);
      x_hi = std::max(x_hi, p[0]);
      y_lo = std::min(y_lo, p[1]);
      y_hi = std::max(y_hi, p[1]);
    }
  }
  std::sort(errors.begin(), errors.end());
  const double p95 =
      errors[static_cast<std::size_t>(0.95 * static_cast<double>(errors.size() - 1))];
  // The colour key spans every error unless a few outliers would squeeze the rest into one
  // colour; then it ends at the 95th percentile and the points beyond get a marker of their own.
  const double key_max = errors.back() > 2.0 * p95 && p95 > 0.0 ? p95 : errors.back();
  std::ostringstream inside, beyond;
  for (const evaluation::LandmarkScore& l : score.last_map) {
    std::ostringstream& out = l.error_m > key_max ? beyond : inside;
    out << Number(l.estimate_m[0]) << ' ' << Number(l.estimate_m[1]) << ' ' << Number(l.truth_m[0])
        << ' ' << Number(l.truth_m[1]) << ' ' << Number(l.error_m) << '\n';
  }
  // Square ranges with a margin, and a strip below the points for the scale bar.
  const double span = std::max({x_hi - x_lo, y_hi - y_lo, 1e-3});
  const double cx = 0.5 * (x_lo + x_hi), cy = 0.5 * (y_lo + y_hi);
  x_lo = cx - 0.55 * span;
  x_hi = cx + 0.55 * span;
  y_hi = cy + 0.55 * span;
  y_lo = cy - 0.70 * span;
  GnuplotJob job(900, 950);
  const std::string in = job.Data("inside.dat", inside.str());
  const std::string out = job.Data("beyond.dat", beyond.str());
  std::ostringstream s;
  s << Preamble() << "set key below\nset size ratio -1\n"
    << "set title 'Landmark map seen from above, the last judged map (frame "
    << score.maps.back().frame_seq << ", " << score.last_map.size() << " landmarks)' font ',12'\n"
    << "set xlabel 'world x (m)'\nset ylabel 'world y (m)'\n"
    << "set xrange [" << Number(x_lo) << ":" << Number(x_hi) << "]\n"
    << "set yrange [" << Number(y_lo) << ":" << Number(y_hi) << "]\n"
    << "set cblabel 'landmark error |estimate − truth| (m)'\n"
    << "set cbrange [0:" << Number(key_max > 0.0 ? key_max : 1e-3) << "]\n"
    << "set palette defined (0 '#1a9850', 0.5 '#fee08b', 1 '#d73027')\n"
    << ScaleBar(x_lo, x_hi, y_lo, y_hi) << "plot " << in
    << " using 3:4 with points pt 6 ps 1.3 lc rgb '#808080' title 'true position', \\\n  " << in
    << " using 1:2:5 with points pt 7 ps 0.8 palette title 'estimate, coloured by its error'";
  if (!beyond.str().empty()) {
    char label[96];
    std::snprintf(label, sizeof label, "estimate with error above the key (> %.3g m)", key_max);
    s << ", \\\n  " << out << " using 3:4 with points pt 6 ps 1.3 lc rgb '#808080' notitle, \\\n  "
      << out << " using 1:2 with points pt 9 ps 1.4 lc rgb 'black' title '" << label << "'";
  }
  s << "\n";
  return job.Render(s.str(), png, error);
}

std::vector<std::string> DrawRun(const evaluation::RunScore& score, const RunPictures& pictures,
                                 const std::string& dir, std::vector<std::string>* errors) {
  std::vector<std::string> written;
  std::string error;
  const auto draw = [&](bool has_data, const std::string& name, auto&& draw_one) {
    if (!has_data) return;
    const std::string png = dir + "/" + name;
    if (draw_one(png)) {
      written.push_back(png);
    } else {
      errors->push_back(error);
    }
  };
  draw(!score.outputs.empty(), "trajectory.png",
       [&](const std::string& png) { return DrawTrajectory(score, png, &error); });
  draw(!score.outputs.empty(), "attitude_error.png",
       [&](const std::string& png) { return DrawAttitudeError(score, png, &error); });
  draw(!score.maps.empty(), "landmark_error.png",
       [&](const std::string& png) { return DrawLandmarkError(score, png, &error); });
  draw(!score.last_map.empty(), "map.png",
       [&](const std::string& png) { return DrawLandmarkMap(score, png, &error); });
  const evaluation::HazardMapView* hazard = pictures.last_hazard_map;
  draw(hazard != nullptr && hazard->cells_per_side > 0, "hazard.png", [&](const std::string& png) {
    std::string title =
        "Hazard map, the last published (frame " + std::to_string(hazard->frame_seq);
    for (const evaluation::HazardScore& h : score.hazard_maps) {
      if (h.frame_seq != hazard->frame_seq || !std::isfinite(h.altitude_m)) continue;
      char text[48];
      std::snprintf(text, sizeof text, ", altitude %.1f m", h.altitude_m);
      title += text;
    }
    return DrawHazardMap(*hazard, pictures.footprint_radius_m, title + ")", png, &error);
  });
  return written;
}

}  // namespace swf::plot
