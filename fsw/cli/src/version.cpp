#include "swf/cli/cli.hpp"

// CMake's project(VERSION), set on this file only: a version bump recompiles one file.
const char* swf::cli::Version() { return SWF_VERSION; }
