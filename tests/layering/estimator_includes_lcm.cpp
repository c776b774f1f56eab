// Deliberate layering violation, never part of the normal build: the estimator may not use LCM.
// tests/layering/CMakeLists.txt builds this under the estimator's rules and expects the failure.
#include <lcm/lcm-cpp.hpp>
