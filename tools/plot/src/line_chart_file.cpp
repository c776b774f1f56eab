// A line chart as a text file (plot.hpp): written by swf-eval beside its JSON, read by
// `swf-plot curves`. The reader is strict, since a file that reads wrong draws a wrong figure:
// every line is either a known header line or a row of exactly x and one value per series.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>

#include "gnuplot_job.hpp"
#include "swf/plot/plot.hpp"

namespace swf::plot {

namespace {

bool OneLine(const std::string& text) { return text.find_first_of("\r\n") == std::string::npos; }

// `"a" "b c"` -> {a, b c}; false when the text is not a list of quoted names.
bool ParseNames(const std::string& text, std::vector<std::string>* names) {
  std::size_t at = text.find_first_not_of(' ');
  while (at != std::string::npos) {
    if (text[at] != '"') return false;
    const std::size_t end = text.find('"', at + 1);
    if (end == std::string::npos) return false;
    names->push_back(text.substr(at + 1, end - at - 1));
    at = text.find_first_not_of(' ', end + 1);
    if (at != std::string::npos && at == end + 1) return false;  // "a""b": no separator
  }
  return !names->empty();
}

// What a header line names, with the value after "key: ".
struct HeaderLine {
  std::string key;
  std::string value;
};

bool ParseHeader(const std::string& line, HeaderLine* header) {
  if (line.rfind("# ", 0) != 0) return false;
  const std::size_t colon = line.find(':');
  if (colon == std::string::npos) return false;
  header->key = line.substr(2, colon - 2);
  const std::size_t value = line.find_first_not_of(' ', colon + 1);
  header->value = value == std::string::npos ? "" : line.substr(value);
  return true;
}

// Reads the file line by line into a chart; each failure names the line.
class ChartReader {
 public:
  explicit ChartReader(std::string path) : path_(std::move(path)) {}

  bool Read(LineChart* chart, std::string* error) {
    std::ifstream in(path_);
    if (!in) return Fail(0, std::string("cannot read: ") + std::strerror(errno), error);
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      if (line.find_first_not_of(" \t") == std::string::npos) continue;
      const bool ok = line[0] == '#' ? Header(line, number, error) : Row(line, number, error);
      if (!ok) return false;
    }
    if (in.bad()) return Fail(number, std::string("read error: ") + std::strerror(errno), error);
    for (const char* key : {"title", "x", "y", "y scale", "series"}) {
      if (seen_.count(key) == 0) {
        return Fail(0, std::string("the header has no '# ") + key + ":' line", error);
      }
    }
    if (rows_ == 0) return Fail(0, "no data rows", error);
    *chart = chart_;
    return true;
  }

 private:
  bool Fail(int line, const std::string& why, std::string* error) const {
    *error = path_;
    if (line > 0) error->append(1, ':').append(std::to_string(line));
    error->append(": ").append(why);
    return false;
  }

  bool Header(const std::string& line, int number, std::string* error) {
    if (rows_ > 0) return Fail(number, "a header line after the data rows", error);
    HeaderLine h;
    if (!ParseHeader(line, &h)) {
      return Fail(number, "expected a header line '# KEY: VALUE' (title, x, y, y scale, series)",
                  error);
    }
    if (seen_.count(h.key) != 0) {
      return Fail(number, "a second '" + h.key + "' line", error);
    }
    if (h.key == "title") {
      chart_.title = h.value;
    } else if (h.key == "x") {
      chart_.x_label = h.value;
    } else if (h.key == "y") {
      chart_.y_label = h.value;
    } else if (h.key == "y scale") {
      if (h.value != "log" && h.value != "linear") {
        return Fail(number, "y scale '" + h.value + "': expected log or linear", error);
      }
      chart_.log_y = h.value == "log";
    } else if (h.key == "series") {
      std::vector<std::string> names;
      if (!ParseNames(h.value, &names)) {
        return Fail(number, "series: expected quoted names separated by spaces (\"a\" \"b\")",
                    error);
      }
      for (const std::string& name : names) chart_.series.push_back({name, {}, {}});
    } else {
      return Fail(number, "unknown header '" + h.key + "' (title, x, y, y scale, series)", error);
    }
    seen_.insert(h.key);
    return true;
  }

  bool Row(const std::string& line, int number, std::string* error) {
    if (chart_.series.empty()) return Fail(number, "a data row before the '# series:' line", error);
    std::istringstream words(line);
    std::vector<std::string> tokens;
    for (std::string word; words >> word;) tokens.push_back(word);
    const std::size_t expected = chart_.series.size() + 1;
    if (tokens.size() != expected) {
      return Fail(number,
                  "expected " + std::to_string(expected) + " numbers (x and " +
                      std::to_string(expected - 1) + " series), found " +
                      std::to_string(tokens.size()),
                  error);
    }
    std::vector<double> values;
    for (std::size_t c = 0; c < tokens.size(); ++c) {
      char* end = nullptr;
      const double v = std::strtod(tokens[c].c_str(), &end);
      const std::string column = "column " + std::to_string(c + 1) + ": ";
      if (end == tokens[c].c_str() || *end != '\0') {
        return Fail(number, column + "'" + tokens[c] + "' is not a number", error);
      }
      if (std::isinf(v) || (c == 0 && std::isnan(v))) {
        return Fail(
            number,
            column + "'" + tokens[c] + "' is not finite" + (c == 0 ? "" : " (nan: no value)"),
            error);
      }
      values.push_back(v);
    }
    for (std::size_t s = 0; s < chart_.series.size(); ++s) {
      chart_.series[s].x.push_back(values[0]);
      chart_.series[s].y.push_back(values[s + 1]);
    }
    ++rows_;
    return true;
  }

  std::string path_;
  LineChart chart_;
  std::set<std::string> seen_;  // the header keys read so far
  int rows_ = 0;
};

}  // namespace

bool WriteLineChart(const LineChart& chart, const std::string& path, std::string* error) {
  const auto fail = [&](const std::string& why) {
    *error = path + ": " + why;
    return false;
  };
  if (chart.series.empty()) return fail("no series to write");
  for (const std::string* text : {&chart.title, &chart.x_label, &chart.y_label}) {
    if (!OneLine(*text)) return fail("a title or axis label holds a line break: " + *text);
  }
  const std::vector<double>& x = chart.series.front().x;
  std::string names;
  for (const Series& s : chart.series) {
    if (!OneLine(s.title) || s.title.find('"') != std::string::npos || s.title.empty()) {
      return fail("series name '" + s.title + "' is empty or holds a '\"' or a line break");
    }
    if (s.x != x || s.y.size() != x.size()) {
      return fail("series '" + s.title + "' does not share the x of '" +
                  chart.series.front().title + "'");
    }
    if (!names.empty()) names += ' ';
    names.append(1, '"').append(s.title).append(1, '"');
  }
  std::ostringstream text;
  text << "# title: " << chart.title << "\n# x: " << chart.x_label << "\n# y: " << chart.y_label
       << "\n# y scale: " << (chart.log_y ? "log" : "linear") << "\n# series: " << names << "\n";
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (!std::isfinite(x[k])) return fail("x value " + std::to_string(k + 1) + " is not finite");
    text << Number(x[k]);
    for (const Series& s : chart.series) text << ' ' << Number(s.y[k]);
    text << '\n';
  }
  std::ofstream out(path);
  out << text.str();
  out.close();
  if (!out) return fail(std::string("cannot write: ") + std::strerror(errno));
  return true;
}

bool ReadLineChart(const std::string& path, LineChart* chart, std::string* error) {
  return ChartReader(path).Read(chart, error);
}

}  // namespace swf::plot
