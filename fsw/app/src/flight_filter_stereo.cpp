// The flight process's stereo-only filter, instantiated once (pipeline.hpp declares it extern).
#include "swf/app/pipeline.hpp"

namespace swf::estimator {
template class SlidingWindowFilter<StereoModel<double>, app::kMaxWindow, app::kMaxLandmarks,
                                   app::kMaxMeasurementsPerPose, app::kMaxPriorLandmarks>;
}  // namespace swf::estimator
