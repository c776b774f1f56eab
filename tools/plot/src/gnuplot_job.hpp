// One gnuplot run (private to tools/plot): a temporary directory that holds the plot's data files
// and script, gnuplot run on the script there with its output captured, and the PNG copied to its
// destination only when gnuplot succeeded. The directory is removed with the job.
#pragma once

#include <cstddef>
#include <string>

namespace swf::plot {

class GnuplotJob {
 public:
  // A canvas of width x height pixels.
  GnuplotJob(int width_px, int height_px);
  ~GnuplotJob();
  GnuplotJob(const GnuplotJob&) = delete;
  GnuplotJob& operator=(const GnuplotJob&) = delete;

  // Writes a data file into the job's directory; returns its path quoted for the script ('...').
  // A write failure is remembered and reported by Render.
  std::string Data(const std::string& name, const std::string& text);
  std::string Binary(const std::string& name, const void* bytes, std::size_t size);
  // Runs gnuplot on `script` (after the terminal and output settings the job writes itself) and
  // copies the PNG to `png`; false with the reason, naming `png`.
  bool Render(const std::string& script, const std::string& png, std::string* error);

 private:
  std::string Write(const std::string& name, const void* bytes, std::size_t size);

  int width_px_;
  int height_px_;
  std::string dir_;  // empty: mkdtemp failed (error_ says why)
  std::string error_;
};

// A string as a gnuplot single-quoted literal (a quote inside is doubled).
std::string Quoted(const std::string& text);
// A title as a gnuplot double-quoted literal, broken into lines at spaces so that each fits a
// canvas width_px wide at font_pt: gnuplot neither wraps nor shrinks a title, it cuts a line
// wider than the canvas at both edges.
std::string TitleQuoted(const std::string& text, int width_px, int font_pt);
// A number for a data file: %.9g, or NaN (gnuplot leaves a gap there).
std::string Number(double v);

}  // namespace swf::plot
