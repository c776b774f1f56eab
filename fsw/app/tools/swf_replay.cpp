// swf-replay: the flight pipeline on the stereo frames of a recorded LCM log.
//   swf-replay --config FILE --log IN.lcmlog [--record OUT.lcmlog] [--set 'key: value']...
#include "swf/app/app.hpp"

int main(int argc, char** argv) { return swf::app::RunFlightProcess(argc, argv, true); }
