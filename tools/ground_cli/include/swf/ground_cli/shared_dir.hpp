// Where the ground programs, benchmarks and tests find the project's shared data (terrain
// imagery, recordings, reference results): the folder SWF_SHARED_DIR names (ctest sets it,
// swf_test()), else ../shared from the working directory, which is the repository's sibling when
// a program runs from the repository's root (tools/run, the tests' scripts).
//
// Its own header without CLI11, so that the tests' support (tests/support) can offer it to every
// test; the flight processes never look for shared data.
#pragma once

#include <string>

namespace swf::ground_cli {

std::string SharedDir();

}  // namespace swf::ground_cli
