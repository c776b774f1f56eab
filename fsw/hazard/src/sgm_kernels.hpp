// The row kernels of SgmMatcher (dense_stereo.hpp), one set per instruction set. Internal to
// swf::hazard. Each kernel computes the same integers in the same order; only the vector width and
// a few reductions differ, so every kernel gives the same bits.
//
// Layouts (all row-major, x in image order):
//  - census: 3 planes of 8 bits per pixel (bit 7 - k % 8 of plane k / 8 is neighbour k of the 5x5
//    window in raster order, centre skipped, set when the neighbour is darker); the right image's
//    rows are stored reversed (index w - 1 - x), so a pixel's costs over d read forward.
//  - costs C(x, d) of one row: cost_stride bytes per pixel, d = 0 .. padded_d - 1.
//  - path vectors L_r(x, .): path_stride int16 per pixel, element d at offset kLead + d; element
//    kLead - 1 and kLead + padded_d hold kBorder; lanes num_d .. padded_d - 1 hold kBorder too.
//  - sums S(x, d): padded_d int16 per pixel.
#pragma once

#include <cstdint>

#include "swf/frontend/image.hpp"
#include "swf/hazard/dense_stereo.hpp"

namespace swf::hazard::sgm_detail {

constexpr int kCensusPlanes = 3;
constexpr int kCostScale = 4;              // Hamming (0..24) x 4
constexpr int kMaxCost = 24 * kCostScale;  // cost where the right pixel is outside the image
constexpr int kDisparityUnit = 16;         // path vectors are padded to a multiple of this
constexpr int kCostUnit = 32;              // cost rows: widest kernel's byte vector
constexpr int kLead = 16;                  // int16 before element 0 of a path vector
// Sentinel for the disparities outside the range. Larger than any candidate of the recursion
// (L <= 96 + p2 <= 1096, min + p2 <= 2096), and 8 paths of it still fit in int16 (32760).
constexpr std::int16_t kBorder = 0x0FFF;

// Census planes of row y of `image` (its width): plane[k] + x, or plane[k] + (w - 1 - x) when
// reversed.
void CensusRow(const frontend::GrayView& image, int y, bool reversed, std::uint8_t* const* plane);

struct CostRowJob {
  const std::uint8_t* left[kCensusPlanes];   // this row's census, image order
  const std::uint8_t* right[kCensusPlanes];  // this row's census, reversed, kCostUnit readable past
  int width = 0;
  int min_disparity = 0;
  int padded_d = 0;
  int cost_stride = 0;  // a multiple of kCostUnit, >= padded_d
  std::uint8_t* cost = nullptr;
};

// One pass over one row: every path of the pass (the 1 or 3 from the previous row and the one along
// the row) for every pixel, in the pass's order; sum_out = sum_in (or 0) + those paths' L.
struct PassRowJob {
  bool forward = true;   // top-down and left to right; else bottom-up and right to left
  int num_vertical = 3;  // paths from the previous row: 1 (straight) or 3 (and diagonals)
  int width = 0;
  int padded_d = 0;
  int path_stride = 0;
  int cost_stride = 0;
  std::int16_t p1 = 0;
  const std::int16_t* p2_table = nullptr;  // adaptive P2 by |dI|
  const std::uint8_t* cost = nullptr;
  const std::uint8_t* image = nullptr;       // this row of the left image
  const std::uint8_t* image_prev = nullptr;  // the previous row along the pass; null: first row
  const std::int16_t* prev_rows = nullptr;   // num_vertical blocks of width * path_stride
  std::int16_t* cur_rows = nullptr;
  const std::int16_t* prev_mins = nullptr;  // num_vertical blocks of width
  std::int16_t* cur_mins = nullptr;
  std::int16_t* horizontal = nullptr;       // 2 * path_stride
  const std::int16_t* start = nullptr;      // path_stride zeros
  const std::int16_t* pad_floor = nullptr;  // padded_d: 0 below num_d, kBorder above
  const std::int16_t* sum_in = nullptr;     // null: the pass's sum starts at 0
  std::int16_t* sum_out = nullptr;
};

// Disparities of one row from its complete sums (see dense_stereo.hpp).
struct SelectRowJob {
  const std::int16_t* sum = nullptr;
  int width = 0;
  int min_disparity = 0;
  int num_d = 0;
  int padded_d = 0;
  float uniqueness = 0.0f;
  float lr_max_diff = 0.0f;
  std::int16_t* window = nullptr;  // 2 * (padded_d + 2 * kDisparityUnit)
  float* right = nullptr;          // width
  float* disparity = nullptr;      // width
  float* confidence = nullptr;     // width
  int num_valid = 0;               // out: valid pixels of the row
};

struct Kernels {
  void (*cost_row)(const CostRowJob&);
  void (*pass_row)(const PassRowJob&);
  void (*select_row)(SelectRowJob*);
};

// kAuto resolved to the fastest supported kernel; any other value unchanged.
SgmKernel Resolve(SgmKernel kernel);
// The kernels of a supported, resolved kernel.
Kernels KernelsOf(SgmKernel kernel);

}  // namespace swf::hazard::sgm_detail
