// swf-sil: the flight process flying the simulated descent, judged against its truth.
//   swf-sil --config FILE [--set 'key: value']... [--progress] [--check]
// See tools/sil/README.md.
#include "swf/sil/sil.hpp"

int main(int argc, char** argv) {
  swf::sil::SimulatedDescent descent;
  return swf::app::RunFlightProcess(argc, argv, {"swf-sil", false, &descent});
}
