// Deliberate layering violation: fsw/core sits below the estimator and may not include it.
#include "swf/estimator/geometry.hpp"
