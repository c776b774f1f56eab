// Compiles the header-only estimator templates under the flight rules (-fno-exceptions,
// -fno-rtti, -Werror, -ffp-contract=off) for the scalar types the project flies.
#include "swf/estimator/geometry.hpp"

namespace swf::estimator {
template struct Pose<double>;
template struct Pose<float>;
template struct StereoCamera<double>;
template struct StereoCamera<float>;
}  // namespace swf::estimator
