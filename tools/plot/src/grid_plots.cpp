// Maps on a grid (the published hazard map, the terrain with its hazard truth) and the contact
// sheet of camera frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "gnuplot_job.hpp"
#include "style.hpp"
#include "swf/plot/plot.hpp"
#include "swf_msgs/hazard_map_t.hpp"

namespace swf::plot {

namespace {

struct ClassKey {
  const char* name;
  int rgb[3];
};

// A square grid drawn as two panels: a height with its colour key, and a class per cell with a
// legend entry per class (and its cell count); an optional marked site with a footprint circle.
struct GridPanels {
  double x0_m = 0.0;  // centre of cell (0, 0)
  double y0_m = 0.0;
  double cell_m = 0.0;
  int size = 0;
  std::vector<float> height_m;   // NaN: unknown (left blank)
  std::vector<int> class_index;  // into keys
  std::vector<ClassKey> keys;
  std::string height_title;
  std::string class_title;
  std::string count_unit = "cells";  // what a class count counts
  std::string unknown_title;         // the legend's word for blank heights ("": none can be)
  bool site = false;
  double site_m[2] = {0.0, 0.0};
  double site_radius_m = 0.0;
  std::string site_title;
};

// The height colour key: the whole range, or the 1st to 99th percentile when a few cells lie far
// outside it (then the label says so and gives the whole range).
std::string HeightKey(const std::vector<float>& height_m) {
  std::vector<float> known;
  for (float h : height_m) {
    if (std::isfinite(h)) known.push_back(h);
  }
  if (known.empty()) return "set cblabel 'height (m)'\n";
  std::sort(known.begin(), known.end());
  const auto at = [&](double q) {
    return known[static_cast<std::size_t>(q * static_cast<double>(known.size() - 1))];
  };
  const double lo = at(0.01), hi = at(0.99), span = std::max(hi - lo, 1e-6);
  if (known.front() >= lo - 0.25 * span && known.back() <= hi + 0.25 * span)
    return "set cblabel 'height (m)'\n";
  char text[256];
  std::snprintf(text, sizeof text,
                "set cbrange [%.9g:%.9g]\nset cblabel 'height (m): colours span the 1st to 99th "
                "percentile; all cells %.2f to %.2f m'\n",
                lo, hi, known.front(), known.back());
  return text;
}

bool DrawGridPanels(const GridPanels& g, const std::string& title, const std::string& png,
                    std::string* error) {
  if (g.size <= 0 || !(g.cell_m > 0.0)) {
    *error = png + ": the grid is empty";
    return false;
  }
  std::ostringstream height, classes;
  std::vector<int> counts(g.keys.size(), 0);
  bool any_height = false;
  for (int j = 0; j < g.size; ++j) {
    for (int i = 0; i < g.size; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * g.size + i;
      const std::string xy = Number(g.x0_m + i * g.cell_m) + ' ' + Number(g.y0_m + j * g.cell_m);
      height << xy << ' ' << Number(g.height_m[c]) << '\n';
      any_height = any_height || std::isfinite(g.height_m[c]);
      const ClassKey& k = g.keys[static_cast<std::size_t>(g.class_index[c])];
      ++counts[static_cast<std::size_t>(g.class_index[c])];
      classes << xy << ' ' << k.rgb[0] << ' ' << k.rgb[1] << ' ' << k.rgb[2] << '\n';
    }
    height << '\n';
    classes << '\n';
  }
  const std::string height_key = HeightKey(g.height_m);
  const double x_lo = g.x0_m - 0.5 * g.cell_m, x_hi = x_lo + g.size * g.cell_m;
  const double y_lo = g.y0_m - 0.5 * g.cell_m, y_hi = y_lo + g.size * g.cell_m;
  constexpr int kWidth = 1240;
  GnuplotJob job(kWidth, 680);
  const std::string h = job.Data("height.dat", height.str());
  const std::string k = job.Data("classes.dat", classes.str());
  const std::string site = job.Data("site.dat", Number(g.site_m[0]) + ' ' + Number(g.site_m[1]) +
                                                    ' ' + Number(g.site_radius_m) + '\n');
  // The site: a footprint circle and a cross, white under black so they show on any colour.
  std::string site_plot;
  if (g.site) {
    if (g.site_radius_m > 0.0) {
      site_plot += ", \\\n  " + site + " using 1:2:3 with circles lw 4 lc rgb 'white' notitle";
      site_plot += ", \\\n  " + site + " using 1:2:3 with circles lw 1.5 lc rgb 'black' notitle";
    }
    site_plot += ", \\\n  " + site + " using 1:2 with points pt 1 ps 3 lw 5 lc rgb 'white' notitle";
    site_plot += ", \\\n  " + site + " using 1:2 with points pt 1 ps 3 lw 2 lc rgb 'black' title " +
                 Quoted(g.site_title);
  }
  std::ostringstream s;
  s << Preamble() << "set multiplot layout 1,2 title " << TitleQuoted(title, kWidth, 13)
    << " font ',13'\n"
    << "set size ratio -1\nset xlabel 'world x (m)'\nset ylabel 'world y (m)'\n"
    << "set xrange [" << Number(x_lo) << ":" << Number(x_hi) << "]\n"
    << "set yrange [" << Number(y_lo) << ":" << Number(y_hi) << "]\n"
    << "set key below left Left reverse maxcols 2\nunset grid\n"
    << "set object 1 rectangle from graph 0,0 to graph 1,1 behind fc rgb '#f0f0f0' "
       "fs solid noborder\n"
    << ScaleBar(x_lo, x_hi, y_lo, y_hi) << "set title " << Quoted(g.height_title) << "\n"
    << height_key
    << "set palette maxcolors 48\nset palette defined (0 '#313695', 0.25 '#74add1', 0.5 "
       "'#ffffbf', 0.75 '#f46d43', 1 '#a50026')\n";
  if (any_height) {
    s << "plot " << h << " using 1:2:3 with image "
      << (g.unknown_title.empty() ? "notitle" : "title " + Quoted(g.unknown_title)) << site_plot
      << "\n";
  } else {
    s << "set cbrange [0:1]\nplot NaN title 'no known cell'" << site_plot << "\n";
  }
  s << "set title " << Quoted(g.class_title) << "\nunset colorbox\nplot " << k
    << " using 1:2:3:4:5 with rgbimage notitle";
  for (std::size_t c = 0; c < g.keys.size(); ++c) {
    char colour[16];
    std::snprintf(colour, sizeof colour, "#%02x%02x%02x", g.keys[c].rgb[0], g.keys[c].rgb[1],
                  g.keys[c].rgb[2]);
    s << ", \\\n  keyentry with boxes fs solid 1.0 fc rgb '" << colour << "' title "
      << Quoted(std::string(g.keys[c].name) + " (" + std::to_string(counts[c]) + " " +
                g.count_unit + ")");
  }
  s << site_plot << "\nunset multiplot\n";
  return job.Render(s.str(), png, error);
}

std::string Fixed1(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", v);
  return text;
}

}  // namespace

bool DrawHazardMap(const evaluation::HazardMapView& map, double footprint_radius_m,
                   const std::string& title, const std::string& png, std::string* error) {
  using M = swf_msgs::hazard_map_t;
  // In the order of hazard_map_t's CLASS_* codes.
  static const std::vector<ClassKey> kKeys = {
      {"unknown", {189, 189, 189}}, {"safe", {116, 196, 118}},      {"too steep", {253, 141, 60}},
      {"rock", {215, 25, 28}},      {"too rough", {158, 154, 200}}, {"uncertain", {255, 230, 110}},
      {"other code", {0, 0, 0}}};
  GridPanels g;
  g.size = map.cells_per_side;
  g.cell_m = map.cell_m;
  g.x0_m = map.origin_world_m[0] + 0.5 * map.cell_m;
  g.y0_m = map.origin_world_m[1] + 0.5 * map.cell_m;
  const std::size_t cells = static_cast<std::size_t>(g.size) * g.size;
  g.height_m.assign(map.elevation_m, map.elevation_m + cells);
  g.class_index.resize(cells);
  for (std::size_t c = 0; c < cells; ++c) {
    const int code = map.hazard_class[c];
    g.class_index[c] = code >= M::CLASS_UNKNOWN && code <= M::CLASS_UNCERTAIN ? code : 6;
  }
  g.keys = kKeys;
  g.height_title = "elevation of each cell";
  g.unknown_title = "blank: unknown elevation";
  g.class_title = "hazard class of each cell";
  g.site = map.site_valid;
  g.site_m[0] = map.site_world_m[0];
  g.site_m[1] = map.site_world_m[1];
  g.site_radius_m = footprint_radius_m;
  g.site_title =
      "chosen safe site (score " + Fixed1(map.site_score) + ")" +
      (footprint_radius_m > 0.0 ? ", lander footprint r = " + Fixed1(footprint_radius_m) + " m"
                                : "");
  if (!map.site_valid) g.class_title += " (no safe site found)";
  return DrawGridPanels(g, title, png, error);
}

bool DrawTerrainHazard(const HeightGrid& terrain, bool target_valid, const double target_m[2],
                       const std::string& title, const std::string& png, std::string* error) {
  const std::size_t nodes = static_cast<std::size_t>(terrain.size) * terrain.size;
  if (terrain.size <= 0 || terrain.height_m.size() != nodes ||
      terrain.hazard_bits.size() != nodes) {
    *error = png + ": the terrain grid and its hazard truth do not match";
    return false;
  }
  // At most 300 blocks a side: the mean height of each block, and its worst hazard (a rock in a
  // block outranks a slope, so no rock disappears when the picture is reduced).
  const int block = (terrain.size + 299) / 300;
  GridPanels g;
  g.size = terrain.size / block;
  g.cell_m = terrain.cell_m * block;
  g.x0_m = terrain.x0_m + 0.5 * (block - 1) * terrain.cell_m;
  g.y0_m = terrain.y0_m + 0.5 * (block - 1) * terrain.cell_m;
  g.height_m.assign(static_cast<std::size_t>(g.size) * g.size, 0.0f);
  g.class_index.assign(g.height_m.size(), 0);
  for (int bj = 0; bj < g.size; ++bj) {
    for (int bi = 0; bi < g.size; ++bi) {
      double sum = 0.0;
      int worst = 0;
      for (int j = bj * block; j < (bj + 1) * block; ++j) {
        for (int i = bi * block; i < (bi + 1) * block; ++i) {
          const std::size_t n = static_cast<std::size_t>(j) * terrain.size + i;
          sum += terrain.height_m[n];
          const std::uint8_t bits = terrain.hazard_bits[n];
          worst = std::max(worst, (bits & 2) != 0 ? 2 : (bits & 1) != 0 ? 1 : 0);
        }
      }
      const std::size_t c = static_cast<std::size_t>(bj) * g.size + bi;
      g.height_m[c] = static_cast<float>(sum / (block * block));
      g.class_index[c] = worst;
    }
  }
  g.keys = {{"safe", {116, 196, 118}}, {"too steep", {253, 141, 60}}, {"rock", {215, 25, 28}}};
  g.height_title = "terrain height";
  if (block > 1) g.count_unit = "blocks";
  g.class_title = block > 1 ? "hazard truth (worst of each " + std::to_string(block) + "x" +
                                  std::to_string(block) + " block of nodes)"
                            : "hazard truth";
  g.site = target_valid;
  if (target_valid) {
    g.site_m[0] = target_m[0];
    g.site_m[1] = target_m[1];
  }
  g.site_title = "descent target";
  return DrawGridPanels(g, title, png, error);
}

bool DrawContactSheet(const std::vector<ContactFrame>& frames, const std::string& title,
                      const std::string& png, std::string* error) {
  if (frames.empty()) {
    *error = png + ": no frame to show";
    return false;
  }
  const int cols = std::min<int>(4, static_cast<int>(frames.size()));
  const int rows = (static_cast<int>(frames.size()) + cols - 1) / cols;
  const ContactFrame& first = frames.front();
  const int tile_w = 320;
  const int tile_h = first.width > 0 ? tile_w * first.height / first.width + 40 : tile_w;
  GnuplotJob job(cols * tile_w, rows * tile_h + 50);
  std::ostringstream s;
  s << "set multiplot layout " << rows << "," << cols << " title "
    << TitleQuoted(title, cols * tile_w, 13)
    << " font ',13'\nunset key\nunset colorbox\nunset tics\nunset border\n"
    << "set palette gray\nset cbrange [0:255]\nset size ratio -1\n"
    << "set lmargin 1\nset rmargin 1\nset tmargin 2\nset bmargin 1\n";
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const ContactFrame& f = frames[k];
    if (f.width <= 0 || f.height <= 0 ||
        f.gray.size() != static_cast<std::size_t>(f.width) * f.height) {
      *error = png + ": frame " + std::to_string(f.frame) + " has no image of its size";
      return false;
    }
    const std::string file =
        job.Binary("frame" + std::to_string(k) + ".gray", f.gray.data(), f.gray.size());
    char label[96];
    std::snprintf(label, sizeof label, "frame %lld, altitude %.1f m",
                  static_cast<long long>(f.frame), f.altitude_m);
    s << "set title '" << label << "'\nset xrange [0:" << f.width << "]\nset yrange [0:" << f.height
      << "]\nplot " << file << " binary array=(" << f.width << "," << f.height
      << ") flipy format='%uchar' with image\n";
  }
  s << "unset multiplot\n";
  return job.Render(s.str(), png, error);
}

namespace {

// The k-th series' colour, point and dash: 8 colours against 7 point shapes, dashed after the
// first 8 series, so no two of a chart's series look alike (NEES plots have a dozen).
std::string SeriesStyle(std::size_t k) {
  static const int kPoints[] = {5, 7, 9, 11, 13, 4, 6};  // filled square, circle, triangles, ...
  return "lc " + std::to_string(k % 8 + 1) + " pt " + std::to_string(kPoints[k % 7]) + " dt " +
         std::to_string(k / 8 % 5 + 1);
}

}  // namespace

bool DrawLineChart(const LineChart& chart, const std::string& png, std::string* error) {
  if (chart.series.empty()) {
    *error = png + ": no series to plot";
    return false;
  }
  constexpr int kWidth = 1000;
  GnuplotJob job(kWidth, 600);
  std::ostringstream s;
  s << Preamble() << "set key outside right top\nset title " << TitleQuoted(chart.title, kWidth, 12)
    << " font ',12'\nset xlabel " << Quoted(chart.x_label) << "\nset ylabel "
    << Quoted(chart.y_label) << "\n"
    << (chart.log_y ? "set logscale y\nset format y '%g'\n" : "") << "plot ";
  for (std::size_t k = 0; k < chart.series.size(); ++k) {
    const Series& series = chart.series[k];
    std::ostringstream data;
    for (std::size_t i = 0; i < series.x.size() && i < series.y.size(); ++i) {
      // A log axis cannot show zero or less: a gap, not a clamp.
      const double y = chart.log_y && !(series.y[i] > 0.0) ? NAN : series.y[i];
      data << Number(series.x[i]) << ' ' << Number(y) << '\n';
    }
    s << (k > 0 ? ", \\\n  " : "") << job.Data("series" + std::to_string(k) + ".dat", data.str())
      << " using 1:2 with linespoints lw 2 " << SeriesStyle(k) << " title " << Quoted(series.title);
  }
  s << "\n";
  return job.Render(s.str(), png, error);
}

}  // namespace swf::plot
