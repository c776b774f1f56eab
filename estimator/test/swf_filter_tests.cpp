// The Sliding Window Filter's test files compiled as one translation unit (estimator_swf_test).
// Compiling the filter is almost all template instantiation, and a unit's first filter instance
// pays for most of it (Eigen's machinery, which later instances with other models and capacities
// reuse): one unit for these files costs a fraction of one unit each, under GCC and clang-tidy
// alike. Each file keeps its own includes and anonymous namespace; names they share must agree.
#include "inertial_model_test.cpp"
#include "swf_integrity_test.cpp"
#include "swf_linear_test.cpp"
#include "swf_stereo_test.cpp"

// The scenario runs are too slow under emulation (the aarch64 tests run under qemu): host only.
#ifdef SWF_SCENARIO_TESTS
#include "inertial_scenario_test.cpp"
#include "swf_scenario_test.cpp"
#endif
