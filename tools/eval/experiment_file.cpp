#include "experiment_file.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "json.hpp"

namespace swf::eval {
namespace {

bool WriteDat(const std::string& path, const std::string& x_label,
              const std::vector<Series>& series, const std::vector<double>& x) {
  std::ofstream dat(path);
  dat << "# " << x_label;
  for (const Series& s : series) dat << " \"" << s.name << "\"";
  dat << "\n";
  const std::size_t n = series.empty() ? 0 : series[0].y.size();
  for (std::size_t k = 0; k < n; ++k) {
    if (k < x.size()) {
      dat << x[k];
    } else {
      dat << k + 1;
    }
    // gnuplot reads "nan" as a missing point; JSON gets null instead.
    for (const Series& s : series) dat << " " << (k < s.y.size() ? s.y[k] : NAN);
    dat << "\n";
  }
  dat.close();
  return static_cast<bool>(dat);
}

}  // namespace

bool WriteExperiment(const std::string& out, const std::string& name, const std::string& x_label,
                     const std::vector<Series>& series, const std::string& extra_json,
                     const std::vector<double>& x) {
  const std::string dat = out + "/" + name + ".dat";
  if (!WriteDat(dat, x_label, series, x)) {
    std::fprintf(stderr, "swf-eval: %s: cannot write\n", dat.c_str());
    return false;
  }
  std::string json =
      "{\n  \"experiment\": " + JsonString(name) + ",\n  \"x\": " + JsonString(x_label) + ",\n";
  if (!extra_json.empty()) json += extra_json + ",\n";
  if (!x.empty()) json += "  \"x_values\": " + JsonArray(x) + ",\n";
  json += "  \"series\": {\n";
  for (std::size_t i = 0; i < series.size(); ++i) {
    json += "    " + JsonString(series[i].name) + ": " + JsonArray(series[i].y) +
            (i + 1 < series.size() ? ",\n" : "\n");
  }
  json += "  }\n}\n";
  std::string error;
  if (!WriteJsonFile(out + "/" + name + ".json", json, &error)) {
    std::fprintf(stderr, "swf-eval: %s\n", error.c_str());
    return false;
  }
  std::printf("swf-eval: wrote %s/%s.json\n", out.c_str(), name.c_str());
  return true;
}

bool MakeDirectories(const std::string& dir, std::string* error) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    *error = dir + ": cannot create the output directory (" +
             (ec ? ec.message() : std::string("exists and is not a directory")) + ")";
    return false;
  }
  return true;
}

}  // namespace swf::eval
