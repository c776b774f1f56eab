// A camera process on the bus, for the end-to-end test of `source: lcm` (lcm_source_test.sh):
// publishes raw stereo_frame_t pairs of a textured plane (right view shifted by a fixed
// disparity, the scene sliding one pixel per frame) at 10 Hz until it has seen `pairs`
// nav_state_t messages of the flight process on NAV_CHANNEL, or for at most 60 s. With --junk,
// once the flight process has answered a frame, one message that is no frame (it must be counted
// as rejected).
// usage: lcm_stereo_publisher URL CHANNEL NAV_CHANNEL WIDTH HEIGHT PAIRS [--junk]
// Exit 0 when the flight process answered every pair, 1 otherwise.
#include <lcm/lcm.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "swf_msgs/stereo_frame_t.hpp"

namespace {

constexpr int kDisparityPx = 8;
constexpr std::int64_t kPeriodUs = 100000;

// Random gray blocks of 6 px: corners everywhere, unambiguous along the epipolar lines.
std::uint8_t Texture(int x, int y) {
  std::uint32_t h = static_cast<std::uint32_t>((x + 4096) / 6) * 73856093U ^
                    static_cast<std::uint32_t>((y + 4096) / 6) * 19349663U;
  h ^= h >> 13;
  h *= 0x5bd1e995U;
  h ^= h >> 15;
  return static_cast<std::uint8_t>(40 + (h % 176));
}

std::int64_t NowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 7) {
    std::fprintf(stderr, "usage: %s URL CHANNEL NAV_CHANNEL WIDTH HEIGHT PAIRS [--junk]\n",
                 argv[0]);
    return 2;
  }
  const char* channel = argv[2];
  const int width = std::atoi(argv[4]);
  const int height = std::atoi(argv[5]);
  const int pairs = std::atoi(argv[6]);
  const bool junk = argc > 7 && std::strcmp(argv[7], "--junk") == 0;
  lcm_t* lcm = lcm_create(argv[1]);
  if (lcm == nullptr) return 1;
  int navs = 0;
  lcm_subscribe(
      lcm, argv[3],
      [](const lcm_recv_buf_t*, const char*, void* count) { ++*static_cast<int*>(count); }, &navs);
  swf_msgs::stereo_frame_t f{};
  f.rectified = false;
  f.width = width;
  f.height = height;
  f.num_bytes = width * height;
  f.left.resize(static_cast<std::size_t>(f.num_bytes));
  f.right.resize(f.left.size());
  std::vector<std::uint8_t> bytes;
  std::int64_t next_us = NowUs();
  bool junk_sent = false;
  for (int k = 0; k < 600 && navs < pairs; ++k) {
    if (junk && !junk_sent && navs > 0) {
      // Once the flight process is known to listen (it answered a frame).
      const std::uint8_t bytes[5] = {1, 2, 3, 4, 5};
      lcm_publish(lcm, channel, bytes, sizeof bytes);
      junk_sent = true;
    }
    f.seq = k;
    f.left_exposure_utime = NowUs();
    f.right_exposure_utime = f.left_exposure_utime;
    f.utime = f.left_exposure_utime;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        f.left[static_cast<std::size_t>(y * width + x)] = Texture(x + k, y);
        f.right[static_cast<std::size_t>(y * width + x)] = Texture(x + k + kDisparityPx, y);
      }
    }
    bytes.resize(static_cast<std::size_t>(f.getEncodedSize()));
    if (f.encode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0 ||
        lcm_publish(lcm, channel, bytes.data(), static_cast<unsigned>(bytes.size())) < 0) {
      std::fprintf(stderr, "lcm_stereo_publisher: cannot publish frame %d\n", k);
      break;
    }
    next_us += kPeriodUs;
    for (std::int64_t left_us = next_us - NowUs(); left_us > 0; left_us = next_us - NowUs()) {
      lcm_handle_timeout(lcm, static_cast<int>(left_us / 1000 + 1));
    }
  }
  std::fprintf(stderr, "lcm_stereo_publisher: %d nav_state_t seen of %d\n", navs, pairs);
  lcm_destroy(lcm);
  return navs >= pairs ? 0 : 1;
}
