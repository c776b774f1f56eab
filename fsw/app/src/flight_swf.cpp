// The flight estimator's one instantiation (pipeline.hpp declares it extern): the filter's
// member definitions are compiled here once instead of in every file that includes the
// pipeline.
#include "swf/app/pipeline.hpp"

namespace swf::estimator {
template class SlidingWindowFilter<StereoModel<double>, app::kMaxWindow, app::kMaxLandmarks,
                                   app::kMaxMeasurementsPerPose, app::kMaxPriorLandmarks>;
}  // namespace swf::estimator
