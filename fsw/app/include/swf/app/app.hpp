// The flight process as a function, shared by swf-fsw and swf-replay (tools/ mains only parse
// argv): configuration -> source -> pipeline -> rate groups -> outputs -> summary.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "swf/app/hazard_stage.hpp"
#include "swf/app/lcm_io.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/core/status.hpp"

namespace swf::app {

struct FswConfig;  // config.hpp

// The flight process's preallocated parts around a source: the frame group's pipeline, the
// hazard stage, the output pools and the output thread (opened, not started). The observers,
// the rate groups and the source are the caller's. swf-fsw, swf-replay and the tests all build
// them with AssembleFlightParts.
struct FlightParts {
  std::unique_ptr<Pipeline> pipeline;
  std::unique_ptr<MapperHazardStage> hazard;
  std::unique_ptr<OutputChannels> channels;
  OutputThread output;
};

// Sizes everything from `po` (the hazard mapper's camera and image size, the pools and the
// output buffers) and allocates it all now. kInvalidArgument: the pipeline or the hazard mapper
// refused its options; kFull: out of memory; kIoError: the output (LCM, the log) did not open.
// `error` says which, for a "configuration refused:" or run-time error line.
core::Status AssembleFlightParts(const PipelineOptions& po,
                                 hazard::HazardMapperOptions hazard_options,
                                 OutputOptions output_options, FlightParts* parts,
                                 std::string* error);

// The configuration's front-end, filter and noise settings into `po` (whose width_px and
// height_px the source has already set); `nav_mode` gets nav_state_t's MODE_* for the filter
// mode. The one place the flight process, its tests and benchmarks take them from.
void ApplyEstimatorConfig(const FswConfig& config, PipelineOptions* po, std::int8_t* nav_mode);

// replay: the source is the log given with --log, paced lockstep unless the config says
// otherwise, input frames are not re-recorded. Exit codes: 0 ok, 1 run-time error (source,
// damaged log record), 2 bad command line or configuration.
int RunFlightProcess(int argc, char** argv, bool replay);

}  // namespace swf::app
