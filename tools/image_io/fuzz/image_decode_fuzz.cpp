// Fuzz entry point for the image decoders: the same bytes go to DecodeGray, DecodeChannel0 and
// DecodeFlo (each picks its format by the leading magic bytes). A decoded image must have the
// size its header states within the limits; a refusal must say why.
#include <cstddef>
#include <cstdint>
#include <string>

#include "swf/image_io/image_io.hpp"

namespace {

void Expect(bool condition) {
  if (!condition) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace swf::image_io;
  std::string error;
  GrayImage image;
  if (DecodeGray(data, size, "input", &image, &error)) {
    Expect(image.width >= 1 && image.width <= kMaxImageSide && image.height >= 1 &&
           image.height <= kMaxImageSide &&
           image.pixels.size() == static_cast<std::size_t>(image.width) * image.height);
  } else {
    Expect(error.rfind("input: ", 0) == 0 && error.size() > 7);
  }
  error.clear();
  if (!DecodeChannel0(data, size, "input", &image, &error)) Expect(!error.empty());
  error.clear();
  FlowField flow;
  if (DecodeFlo(data, size, "input", &flow, &error)) {
    Expect(flow.uv.size() == 2 * static_cast<std::size_t>(flow.width) * flow.height);
  } else {
    Expect(!error.empty());
  }
  return 0;
}
