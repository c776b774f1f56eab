// Deliberate layering violation: the estimator may not see the generated message headers.
#include "swf_msgs/nav_state_t.hpp"
