// The inertial flight estimator's one instantiation (pipeline.hpp declares it extern), in a
// file of its own so that it compiles in parallel with the stereo one (flight_swf.cpp).
#include "swf/app/pipeline.hpp"

namespace swf::estimator {
template class SlidingWindowFilter<InertialStereoModel<double>, app::kMaxWindow, app::kMaxLandmarks,
                                   app::kMaxMeasurementsPerPose, app::kMaxPriorLandmarks>;
}  // namespace swf::estimator
