// ImageView: a rectangle of pixels owned elsewhere, the one image type that crosses module
// boundaries (a camera pair from drivers/, a front-end image, a hazard-map input).
#pragma once

#include <cstddef>
#include <type_traits>

namespace swf::core {

// Row y starts at data + y * stride. The stride counts elements, not bytes: for 8-bit pixels the
// two coincide, and wider pixel types (float responses, 16-bit raw) index by element, as pointer
// arithmetic on T* does.
template <typename T>
struct ImageView {
  T* data = nullptr;
  int width = 0;
  int height = 0;
  int stride = 0;

  T* Row(int y) const { return data + static_cast<std::ptrdiff_t>(y) * stride; }
  T& At(int x, int y) const { return Row(y)[x]; }
  bool Valid() const { return data != nullptr && width > 0 && height > 0 && stride >= width; }
  // Read-only view of the same pixels.
  ImageView<const T> Const() const { return ImageView<const T>{data, width, height, stride}; }
  // Mutable views convert to read-only ones, as T* converts to const T*.
  operator ImageView<const T>() const requires(!std::is_const_v<T>) { return Const(); }
};

}  // namespace swf::core
