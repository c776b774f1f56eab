// swf-fsw: the flight process. swf-fsw --config FILE [--set 'key: value']... [--progress] [--check]
// Flies cameras (v4l2, aravis) and recorded logs; the simulated descent is swf-sil's (tools/sil).
// See fsw/app/README.md.
#include "swf/app/app.hpp"

int main(int argc, char** argv) { return swf::app::RunFlightProcess(argc, argv, {}); }
