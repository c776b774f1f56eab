// swf-eval's real-data commands on image sequences through the flight pipeline:
//   swf-eval euroc DIR [--out OUT] [--window K] [--max-tracks N] [--motion-sigma M,RAD]
//                      [--loop-seconds S] [--divergence-m M]
//   swf-eval kitti DIR [--out OUT] [--window K] [--max-tracks N] [--max-disparity D]
//                      [--motion-sigma M,RAD] [--divergence-m M] [--frames N]
// Each writes OUT/<prefix>.json (valid JSON: a value that does not exist is null with a
// "<key>_reason"), OUT/<prefix>.md (text computed from the same numbers), OUT/<prefix>_error.dat
// and .json (per-frame errors) and the estimated trajectories. Exit status: 0 when every run
// is scored, 1 for unusable input or unwritable output (with the reason on stderr), 2 for bad
// arguments, 3 when a run failed (non-finite, diverged, or frames without a tracked landmark;
// the reason names the frame and the line of the input it came from).
#pragma once

namespace swf::eval {

inline constexpr int kExitRunFailed = 3;

int RunEurocCommand(int argc, char** argv);
int RunKittiCommand(int argc, char** argv);

// The usage lines of both commands.
const char* SequenceUsage();

}  // namespace swf::eval
