// The flight process's stereo-inertial filter, instantiated once (pipeline.hpp declares it extern).
#include "swf/app/pipeline.hpp"

namespace swf::estimator {
template class SlidingWindowFilter<InertialStereoModel<double>, app::kMaxWindow, app::kMaxLandmarks,
                                   app::kMaxMeasurementsPerPose, app::kMaxPriorLandmarks>;
}  // namespace swf::estimator
