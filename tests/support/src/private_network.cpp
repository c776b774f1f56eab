#include "swf/testing/private_network.hpp"

#include <sched.h>

#include <cstdlib>
#include <string>

namespace swf::testing {

bool EnterPrivateNetwork(const char* setup) {
  if (unshare(CLONE_NEWNET) != 0) {
    if (unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) return false;  // neither root nor userns
  }
  const std::string command = std::string("ip link set lo up && ") + setup;
  return std::system(command.c_str()) == 0;
}

}  // namespace swf::testing
