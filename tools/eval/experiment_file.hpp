// One experiment's output files: OUT/NAME.dat (gnuplot columns: x, then one column per series)
// and OUT/NAME.json (the same series plus experiment-specific summary fields). The JSON is
// checked before it is written (ValidateJson), so a non-finite summary value fails the write
// with a reason instead of leaving a file no JSON reader accepts.
#pragma once

#include <string>
#include <vector>

namespace swf::eval {

struct Series {
  std::string name;
  std::vector<double> y;
};

// extra_json: summary fields as JSON object members ("  \"key\": value, ..." without braces),
// or "". x: the abscissa of every row (default 1, 2, 3, ...). False (with a message on stderr
// naming the file) when a file cannot be written or the JSON would not be valid.
[[nodiscard]] bool WriteExperiment(const std::string& out, const std::string& name,
                                   const std::string& x_label, const std::vector<Series>& series,
                                   const std::string& extra_json,
                                   const std::vector<double>& x = {});

// Creates `dir` and its parents (mkdir -p); false with *error naming it.
bool MakeDirectories(const std::string& dir, std::string* error);

}  // namespace swf::eval
