// The flight process as a function, shared by swf-fsw and swf-replay (tools/ mains only parse
// argv): configuration -> source -> pipeline -> rate groups -> outputs -> summary.
#pragma once

namespace swf::app {

// replay: the source is the log given with --log, paced lockstep unless the config says
// otherwise, input frames are not re-recorded. Exit codes: 0 ok, 1 run-time error (source,
// damaged log record), 2 bad command line or configuration.
int RunFlightProcess(int argc, char** argv, bool replay);

}  // namespace swf::app
