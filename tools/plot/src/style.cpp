#include "style.hpp"

#include <cmath>
#include <cstdio>

namespace swf::plot {

std::string Preamble() {
  return "set grid lc rgb '#e0e0e0' lt 1\n"
         "set border lc rgb '#404040'\n"
         "set key opaque box lc rgb '#c0c0c0'\n";
}

std::int64_t TimeOriginUs(const evaluation::RunScore& score) {
  if (!score.outputs.empty()) return score.outputs.front().utime;
  return score.maps.empty() ? 0 : score.maps.front().utime;
}

double Seconds(std::int64_t utime, std::int64_t origin_us) {
  return static_cast<double>(utime - origin_us) * 1e-6;
}

std::string ScaleBar(double x_lo, double x_hi, double y_lo, double y_hi) {
  const double target = (x_hi - x_lo) / 5.0;
  if (!(target > 0.0) || !std::isfinite(target)) return "";
  const double decade = std::pow(10.0, std::floor(std::log10(target)));
  double length = decade;
  for (double step : {2.0, 5.0}) {
    if (step * decade <= target) length = step * decade;
  }
  const double x0 = x_lo + 0.04 * (x_hi - x_lo);
  const double y0 = y_lo + 0.04 * (y_hi - y_lo);
  char text[512];
  std::snprintf(text, sizeof text,
                "set arrow from %.9g,%.9g to %.9g,%.9g nohead front lw 4 lc rgb 'white'\n"
                "set arrow from %.9g,%.9g to %.9g,%.9g nohead front lw 2 lc rgb 'black'\n"
                "set label '%g m' at %.9g,%.9g center front offset 0,0.8 "
                "tc rgb 'black' boxed\n",
                x0, y0, x0 + length, y0, x0, y0, x0 + length, y0, length, x0 + 0.5 * length, y0);
  return "set style textbox opaque noborder fc rgb 'white'\n" + std::string(text);
}

}  // namespace swf::plot
