#include "swf/sim/image_io.hpp"

#include <stb_image.h>
#include <stb_image_write.h>

#include <cstdio>

namespace swf::sim {

core::Status ReadGrayImage(const std::string& path, GrayImage* image) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return core::Status::kIoError;
  int width = 0;
  int height = 0;
  int channels = 0;
  stbi_uc* data = stbi_load_from_file(file, &width, &height, &channels, 1);
  std::fclose(file);
  if (data == nullptr) return core::Status::kCorruptData;
  image->width = width;
  image->height = height;
  image->pixels.assign(data, data + static_cast<size_t>(width) * height);
  stbi_image_free(data);
  return core::Status::kOk;
}

core::Status WritePng(const std::string& path, const std::uint8_t* pixels, std::int32_t width,
                      std::int32_t height, std::int32_t channels, std::int32_t stride_bytes) {
  if (pixels == nullptr || width <= 0 || height <= 0 || (channels != 1 && channels != 3) ||
      stride_bytes < width * channels) {
    return core::Status::kInvalidArgument;
  }
  const int ok = stbi_write_png(path.c_str(), width, height, channels, pixels, stride_bytes);
  return ok != 0 ? core::Status::kOk : core::Status::kIoError;
}

}  // namespace swf::sim
