// Where a dataset reader (euroc.cpp, euroc_imu.cpp, kitti.cpp) turns a path into a stream: every
// reader refuses a missing or unreadable file in the same words, "<path>: cannot open".
#pragma once

#include <fstream>
#include <string>

namespace swf::eval {

// Opens `path` into *file; false with *error set when it cannot.
inline bool OpenInput(const std::string& path, std::ifstream* file, std::string* error) {
  file->open(path);
  if (*file) return true;
  *error = path + ": cannot open";
  return false;
}

}  // namespace swf::eval
