// Compile-time capacities of the vision front end, gathered in one place (STYLE.md, memory).
// Every buffer of the front end is sized from these constants and lives inside an object created
// at start-up, so no per-frame call allocates.
#pragma once

#include <cstddef>
#include <cstdint>

namespace swf::frontend {

// Largest image the front end accepts (pixels). 1408 x 1152 covers the 1282 x 1110 Middlebury
// pair, a 1024 x 768 flight camera and the 752 x 480 EuRoC camera.
inline constexpr int kMaxImageWidth = 1408;
inline constexpr int kMaxImageHeight = 1152;
inline constexpr std::size_t kMaxPixels =
    static_cast<std::size_t>(kMaxImageWidth) * static_cast<std::size_t>(kMaxImageHeight);

// Detector output per call before stereo matching.
inline constexpr std::size_t kMaxCorners = 2048;
// Landmarks tracked at once (the estimator's active map is at most this large).
inline constexpr std::size_t kMaxTracks = 512;
// New landmarks proposed per frame.
inline constexpr std::size_t kMaxNewLandmarks = 512;
// Spatial buckets of the detector grid and candidates kept per bucket before selection.
inline constexpr int kMaxBuckets = 4096;
inline constexpr int kMaxCandidatesPerBucket = 8;
// LK patches: radius up to 7 (15 x 15 pixels).
inline constexpr int kMaxPatchRadius = 7;
inline constexpr int kMaxPatchPixels = (2 * kMaxPatchRadius + 1) * (2 * kMaxPatchRadius + 1);
// Recovery search of a lost track: radius of the whole-pixel window around the prediction.
inline constexpr int kMaxSearchRadius = 16;
// Image pyramid levels for translation-only LK without a geometric prediction.
inline constexpr int kMaxPyramidLevels = 4;
// Disparity search range limit of the SAD matcher.
inline constexpr int kMaxDisparity = 256;

}  // namespace swf::frontend
