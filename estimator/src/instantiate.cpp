// Compiles every member of the header-only estimator templates under the flight rules
// (-fno-exceptions, -fno-rtti, -Werror, -ffp-contract=off) for the scalar the project flies,
// including members no flight code calls yet.
#include "swf/estimator/geometry.hpp"
#include "swf/estimator/imu_preintegration.hpp"
#include "swf/estimator/imu_stream.hpp"

namespace swf::estimator {
template struct Pose<double>;
template struct StereoCamera<double>;
template class ImuPreintegration<double>;
template class ImuStreamChecker<double>;
}  // namespace swf::estimator
