// The flight process as a function, shared by swf-fsw and swf-replay (tools/ mains only parse
// argv): configuration -> source -> pipeline -> rate groups -> outputs -> summary.
#pragma once

#include <cstdint>

namespace swf::app {

struct FswConfig;        // config.hpp
struct PipelineOptions;  // pipeline.hpp

// The configuration's front-end, filter and noise settings into `po` (whose width_px and
// height_px the source has already set); `nav_mode` gets nav_state_t's MODE_* for the filter
// mode. The one place the flight process, its tests and benchmarks take them from.
void ApplyEstimatorConfig(const FswConfig& config, PipelineOptions* po, std::int8_t* nav_mode);

// replay: the source is the log given with --log, paced lockstep unless the config says
// otherwise, input frames are not re-recorded. Exit codes: 0 ok, 1 run-time error (source,
// damaged log record), 2 bad command line or configuration.
int RunFlightProcess(int argc, char** argv, bool replay);

}  // namespace swf::app
