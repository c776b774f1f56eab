// Where a dataset reader (euroc.cpp, euroc_imu.cpp, kitti.cpp) turns a path into a stream: every
// reader refuses a missing or unreadable file in the same words, "<path>: cannot open", and a
// reader whose parser takes any stream (the fuzzers feed it memory) is that parser on the file.
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

// `parse(stream, path, out, error)` on the file at `path`.
template <typename T, typename Parse>
bool ParseFile(const std::string& path, const Parse& parse, T* out, std::string* error) {
  std::ifstream file;
  return OpenInput(path, &file, error) && parse(file, path, out, error);
}

}  // namespace swf::eval
