#include "experiment_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <system_error>

#include "json.hpp"
#include "swf/plot/plot.hpp"

namespace swf::eval {
namespace {

// The series as a line chart over x (1, 2, 3, ... when x is empty), each padded with NaN to the
// longest; false when x is given and does not have a value per row.
bool ChartOf(const Figure& figure, const std::vector<Series>& series, const std::vector<double>& x,
             plot::LineChart* chart, std::string* error) {
  std::size_t rows = 0;
  for (const Series& s : series) rows = std::max(rows, s.y.size());
  if (!x.empty() && x.size() != rows) {
    *error = std::to_string(x.size()) + " x values for series of up to " + std::to_string(rows);
    return false;
  }
  std::vector<double> abscissa = x;
  for (std::size_t k = abscissa.size(); k < rows; ++k) {
    abscissa.push_back(static_cast<double>(k + 1));
  }
  *chart = {figure.title, figure.x_label, figure.y_label, figure.log_y, {}};
  for (const Series& s : series) {
    std::vector<double> y = s.y;
    y.resize(rows, NAN);
    chart->series.push_back({s.name, abscissa, y});
  }
  return true;
}

}  // namespace

bool WriteExperiment(const std::string& out, const std::string& name, const Figure& figure,
                     const std::vector<Series>& series, const std::string& extra_json,
                     const std::vector<double>& x) {
  const std::string dat = out + "/" + name + ".dat";
  plot::LineChart chart;
  std::string error;
  if (!ChartOf(figure, series, x, &chart, &error)) {
    std::fprintf(stderr, "swf-eval: %s: %s\n", dat.c_str(), error.c_str());
    return false;
  }
  if (!plot::WriteLineChart(chart, dat, &error)) {
    std::fprintf(stderr, "swf-eval: %s\n", error.c_str());
    return false;
  }
  std::string json = "{\n  \"experiment\": " + JsonString(name) +
                     ",\n  \"title\": " + JsonString(figure.title) +
                     ",\n  \"x\": " + JsonString(figure.x_label) +
                     ",\n  \"y\": " + JsonString(figure.y_label) + ",\n";
  if (!extra_json.empty()) json += extra_json + ",\n";
  if (!x.empty()) json += "  \"x_values\": " + JsonArray(x) + ",\n";
  json += "  \"series\": {\n";
  for (std::size_t i = 0; i < series.size(); ++i) {
    json += "    " + JsonString(series[i].name) + ": " + JsonArray(series[i].y) +
            (i + 1 < series.size() ? ",\n" : "\n");
  }
  json += "  }\n}\n";
  if (!WriteJsonFile(out + "/" + name + ".json", json, &error)) {
    std::fprintf(stderr, "swf-eval: %s\n", error.c_str());
    return false;
  }
  std::printf("swf-eval: wrote %s/%s.json\n", out.c_str(), name.c_str());
  return true;
}

}  // namespace swf::eval
