// Where the tests find the shared data (imagery, recordings, reference results): the directory
// SWF_SHARED_DIR names (ctest sets it, swf_test()), else ../shared from the working directory.
#pragma once

#include <cstdlib>
#include <string>

namespace swf::testing {

inline std::string SharedDir() {
  const char* dir = std::getenv("SWF_SHARED_DIR");
  return dir != nullptr ? dir : "../shared";
}

}  // namespace swf::testing
