// swf-fsw: the flight process. swf-fsw --config FILE [--set 'key: value']... [--progress]
// See fsw/app/README.md.
#include "swf/app/app.hpp"

int main(int argc, char** argv) { return swf::app::RunFlightProcess(argc, argv, false); }
