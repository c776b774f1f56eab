// The filter instances of swf-eval's experiments (run_filter.hpp), compiled once.
#include "run_filter.hpp"

namespace swf::estimator {
template class SlidingWindowFilter<StereoModel<double>, 40, 300, 200, 160>;
template class SlidingWindowFilter<StereoModel<double>, 160, 4000, 64, 1>;
template class SlidingWindowFilter<InverseDepthStereoModel<double>, 40, 300, 200, 160>;
}  // namespace swf::estimator
