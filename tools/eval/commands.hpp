// swf-eval's real-data commands on image sequences through the flight pipeline:
//   swf-eval euroc DIR [--out OUT] [--window K] [--max-tracks N] [--motion-sigma M,RAD]
//                      [--loop-seconds S] [--divergence-m M] [--measurements FILE]
//   swf-eval kitti DIR [--out OUT] [--window K] [--max-tracks N] [--max-disparity D]
//                      [--motion-sigma M,RAD] [--divergence-m M] [--frames N]
//                      [--measurements FILE]
// Each writes OUT/<prefix>.json (valid JSON: a value that does not exist is null with a
// "<key>_reason"; the command line echoed as "run"), OUT/<prefix>.md (text computed from the same
// numbers), OUT/<prefix>_error.dat and .json (per-frame errors) and the estimated trajectories.
// Exit status: 0 when every run is scored, 1 for unusable input or unwritable output (with the
// reason on stderr), 2 for bad arguments (swf-eval's command line, and a --measurements FILE that
// is one of the files the report writes), 3 when a run failed (non-finite, diverged, or frames
// without a tracked landmark; the reason names the frame and the line of the input it came from).
#pragma once

#include <string>

#include "json.hpp"

namespace swf::eval {

inline constexpr int kExitBadArguments = 2;  // as CLI11's refusals, and --measurements naming
                                             // a file of the report
inline constexpr int kExitRunFailed = 3;

// The options both commands share (swf-eval's command line checks their ranges).
struct SequenceArgs {
  std::string dir;
  std::string out = "out/eval";
  int window = 5;
  int max_tracks = 0;           // 0: the command's default
  double motion_sigma_m = 0.0;  // 0: the command's default (with motion_sigma_rad)
  double motion_sigma_rad = 0.0;
  double divergence_m = 0.0;  // 0: the command's default
  std::string measurements;   // non-empty: the SWF run's measurements as JSON (RunOptions)
  Json run;                   // echoed into every JSON file: swf::ground_cli::RunEcho
};

// `loop_seconds` > 0: the recorded frames played forwards and backwards for that long.
int RunEurocCommand(const SequenceArgs& args, double loop_seconds);
// `max_frames` 0: every frame.
int RunKittiCommand(const SequenceArgs& args, int max_disparity_px, int max_frames);

}  // namespace swf::eval
