// What the plots share (private to tools/plot): colours, the time axis, the map scale bar.
#pragma once

#include <string>

#include "swf/evaluation/run_judge.hpp"

namespace swf::plot {

// The truth is drawn wide and light beneath the estimate, the estimate thin and dark on top.
inline constexpr const char* kTruthStyle = "lw 7 lc rgb '#9ecae1'";
inline constexpr const char* kEstimateStyle = "lw 1.5 lc rgb '#c0392b'";
inline constexpr const char* kBandStyle = "fs solid 1.0 noborder fc rgb '#c7e9c0'";
inline constexpr const char* kTimeLabel = "time since the first navigation output (s)";

// Grid, border and key defaults of every plot.
std::string Preamble();
// The run's time origin: its first navigation output (its first landmark map without outputs).
std::int64_t TimeOriginUs(const evaluation::RunScore& score);
double Seconds(std::int64_t utime, std::int64_t origin_us);
// A scale bar of a round length (1, 2 or 5 x 10^k m, about a fifth of the width) in the lower left
// of a map whose ranges are [x_lo, x_hi] x [y_lo, y_hi] (the caller leaves room for it there).
std::string ScaleBar(double x_lo, double x_hi, double y_lo, double y_hi);

}  // namespace swf::plot
