// One experiment's output files: OUT/NAME.dat (its figure: title, axis labels, y scale, then
// gnuplot columns: x and one column per series; swf::plot::WriteLineChart's format, drawn by
// `swf-plot curves`) and OUT/NAME.json (the same series plus experiment-specific summary fields).
// The JSON is checked before it is written (ValidateJson), so a non-finite summary value fails the
// write with a reason instead of leaving a file no JSON reader accepts.
#pragma once

#include <string>
#include <vector>

namespace swf::eval {

struct Series {
  std::string name;
  std::vector<double> y;
};

// What the figure drawn from OUT/NAME.dat shows, for a reader who has not read the code.
struct Figure {
  std::string title;    // what it shows: "Fig. 13: landmark error on the descent, ..."
  std::string x_label;  // with its unit: "frame number", "average track length (frames)"
  std::string y_label;  // with its unit: "landmark mean squared error (m^2)"
  bool log_y = false;   // the values span decades
};

// extra_json: summary fields as JSON object members ("  \"key\": value, ..." without braces),
// or "". x: the abscissa of every row (default 1, 2, 3, ...); a series shorter than the longest
// has no value (NaN, a gap) in the rows beyond its end. False (with a message on stderr naming
// the file) when a file cannot be written or the JSON would not be valid.
[[nodiscard]] bool WriteExperiment(const std::string& out, const std::string& name,
                                   const Figure& figure, const std::vector<Series>& series,
                                   const std::string& extra_json,
                                   const std::vector<double>& x = {});

}  // namespace swf::eval
