#include "experiment_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "swf/ground_cli/ground_cli.hpp"
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

bool WriteExperiment(const Output& out, const std::string& name, const Figure& figure,
                     const std::vector<Series>& series, const Json& summary,
                     const std::vector<double>& x) {
  const std::string dat = out.dir + "/" + name + ".dat";
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
  Json json = {
      {"experiment", name}, {"title", figure.title}, {"x", figure.x_label}, {"y", figure.y_label}};
  if (summary.is_object()) json.update(summary);
  if (!x.empty()) json["x_values"] = Numbers(x);
  Json values = Json::object();
  for (const Series& s : series) values[s.name] = Numbers(s.y);
  json["series"] = values;
  json["run"] = out.run;
  const std::string path = out.dir + "/" + name + ".json";
  if (!ground_cli::WriteJson(path, json, &error)) {
    std::fprintf(stderr, "swf-eval: %s\n", error.c_str());
    return false;
  }
  std::printf("swf-eval: wrote %s\n", path.c_str());
  return true;
}

}  // namespace swf::eval
