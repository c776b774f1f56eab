// One experiment's output files: OUT/NAME.dat (its figure: title, axis labels, y scale, then
// gnuplot columns: x and one column per series; swf::plot::WriteLineChart's format, drawn by
// `swf-plot curves`) and OUT/NAME.json (the same series plus experiment-specific summary fields
// and the run that wrote it). A non-finite summary value is null with its "<key>_reason"
// (SetNumber), a gap in a series null.
#pragma once

#include <string>
#include <vector>

#include "json.hpp"

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

// Where an experiment's files go, and the run echoed into each of its JSON files.
struct Output {
  std::string dir;
  Json run;  // swf::ground_cli::RunEcho of the command line that writes them
};

// summary: fields of the experiment (a JSON object, may be empty) between the figure's labels and
// the series. x: the abscissa of every row (default 1, 2, 3, ...); a series shorter than the
// longest has no value (NaN, a gap) in the rows beyond its end. False (with a message on stderr
// naming the file) when a file cannot be written or the JSON would not be valid.
[[nodiscard]] bool WriteExperiment(const Output& out, const std::string& name, const Figure& figure,
                                   const std::vector<Series>& series, const Json& summary,
                                   const std::vector<double>& x = {});

}  // namespace swf::eval
