// Compiles the header-only estimator templates under the flight rules (-fno-exceptions,
// -fno-rtti, -Werror, -ffp-contract=off) for the scalar types the project flies.
#include "swf/estimator/geometry.hpp"
#include "swf/estimator/imu_preintegration.hpp"
#include "swf/estimator/imu_stream.hpp"

namespace swf::estimator {
template struct Pose<double>;
template struct Pose<float>;
template struct StereoCamera<double>;
template struct StereoCamera<float>;
template class ImuPreintegration<double>;
template class ImuPreintegration<float>;
template class ImuStreamChecker<double>;
template class ImuStreamChecker<float>;
}  // namespace swf::estimator
