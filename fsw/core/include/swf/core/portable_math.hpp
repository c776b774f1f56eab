// Math with the same bits on every flight platform. The C library's hypot differs by an ulp
// between Debian's x86-64 and arm64 builds (docs/aarch64.md); sqrt, +, - and * are correctly
// rounded everywhere (IEEE 754; the flight code is built without contraction into fused
// multiply-adds). Arguments are bounded image and map coordinates, far from overflow.
#pragma once

#include <cmath>

namespace swf::core {

inline double Hypot(double x, double y) { return std::sqrt(x * x + y * y); }

}  // namespace swf::core
