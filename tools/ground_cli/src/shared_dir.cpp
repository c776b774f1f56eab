#include "swf/ground_cli/shared_dir.hpp"

#include <cstdlib>

namespace swf::ground_cli {

std::string SharedDir() {
  const char* dir = std::getenv("SWF_SHARED_DIR");
  return dir != nullptr ? dir : "../shared";
}

}  // namespace swf::ground_cli
