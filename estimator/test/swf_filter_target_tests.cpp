// estimator_swf_test on the flight target (the aarch64 build, run under qemu): the filter's test
// files for the models the flight process flies (the stereo-inertial filter, and the stereo
// filter's integrity: gates, restarts, allocation-free gated frames). The linear-model identities
// and the stereo filter's modes and robustness (swf_linear_test.cpp, swf_stereo_test.cpp) are
// properties of the algorithm, tested on the host; each distinct filter instance is most of this
// unit's compile time and their runs most of its emulated run time. The flight's own instances
// meet the host's in tests/cross_isa, output for output. As in swf_filter_tests.cpp, one unit.
#include "inertial_model_test.cpp"
#include "swf_integrity_test.cpp"
