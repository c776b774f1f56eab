// Where the tests find the shared data (imagery, recordings, reference results): the ground
// programs' rule (swf::ground_cli::SharedDir), so a test reads what the tool it checks would.
// Not in the flight-only build (no ground programs there, and no test that reads shared data).
#pragma once

#include "swf/ground_cli/shared_dir.hpp"

namespace swf::testing {

using ground_cli::SharedDir;

}  // namespace swf::testing
