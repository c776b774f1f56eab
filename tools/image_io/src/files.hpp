// Reading a whole file with its size bounded before anything is read (images, flow fields and
// calibrations alike). Internal to image_io.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace swf::image_io::internal {

// The whole file, refused (naming it) when it is not a regular file or is larger than max_bytes.
bool ReadBytes(const std::string& path, std::size_t max_bytes, std::vector<std::uint8_t>* bytes,
               std::string* error);

}  // namespace swf::image_io::internal
