// swf-replay: the flight pipeline on the stereo frames of a recorded LCM log.
//   swf-replay --config FILE --log IN.lcmlog [--record OUT.lcmlog] [--set 'key: value']...
// A log of a simulated descent starts from the same truth as the run that recorded it.
#include "swf/sil/sil.hpp"

int main(int argc, char** argv) {
  swf::sil::SimulatedDescent descent;
  return swf::app::RunFlightProcess(argc, argv, {"swf-replay", true, &descent});
}
