// Files for tests that write and read them: a scratch directory removed with its contents at the
// end of the test, and the small checks and reads such tests make on what a program wrote.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>  // mkdtemp

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

namespace swf::testing {

class ScratchDir {
 public:
  // /tmp/swf_test_XXXXXX, unique to this directory's life (short: messages quote the paths
  // whole). A failure to make it fails the test (and leaves Path() empty: nothing is removed).
  ScratchDir() {
    std::string name = "/tmp/swf_test_XXXXXX";
    if (::mkdtemp(name.data()) != nullptr) {
      path_ = name;
    } else {
      ADD_FAILURE() << "cannot make the scratch directory " << name;
    }
  }
  ~ScratchDir() {
    std::error_code ignored;
    if (!path_.empty()) std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::string& Path() const { return path_; }
  // Writes `text` (as bytes) to Path()/name and returns that path.
  std::string Write(const std::string& name, const std::string& text) const {
    const std::string file = path_ + "/" + name;
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

 private:
  std::string path_;
};

// True when something (a file or a directory) is at `path`.
inline bool Exists(const std::string& path) {
  std::error_code ignored;
  return std::filesystem::exists(path, ignored);
}

// The whole file as text ("" when it cannot be read).
inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace swf::testing
