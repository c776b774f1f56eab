#include "files.hpp"

#include <filesystem>
#include <fstream>
#include <iterator>

namespace swf::image_io::internal {

// The whole file, refused (naming it) when it is not a regular file or is larger than max_bytes:
// its size is known before anything is read.
bool ReadBytes(const std::string& path, std::size_t max_bytes, std::vector<std::uint8_t>* bytes,
               std::string* error) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    *error = path + ": cannot open (no such file)";
    return false;
  }
  if (!std::filesystem::is_regular_file(status)) {
    *error = path + ": not a regular file";
    return false;
  }
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || size > max_bytes) {
    *error =
        path + ": " +
        (ec ? "cannot read its size"
            : std::to_string(size) + " bytes, above the limit of " + std::to_string(max_bytes));
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  bytes->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad() || bytes->size() != size) {
    *error = path + ": read error";
    return false;
  }
  return true;
}

}  // namespace swf::image_io::internal
