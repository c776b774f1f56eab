// A camera process on the bus, for the end-to-end tests of `source: lcm` (lcm_source_test.sh):
// publishes raw stereo_frame_t pairs of a textured plane (right view shifted by a fixed
// disparity, the scene sliding one pixel per frame) at 10 Hz until the flight process, having
// answered with nav_state_t on NAV_CHANNEL, falls silent for 1 s (or for at most 60 s). With
// --junk, once the flight process has answered a frame, one message that is no frame (it must be
// counted as rejected). With --imu CHANNEL it is also the vehicle's IMU: the rig stands still (the
// scene does not slide) and before each pair the 200 Hz imu_t samples of the interval up to its
// exposure go out on CHANNEL, stamped on the exposures' clock: no rotation, the specific force
// of gravity for a camera looking at the plane horizontally (camera y axis down).
// usage: lcm_stereo_publisher URL CHANNEL NAV_CHANNEL WIDTH HEIGHT PAIRS [--junk] [--imu CHANNEL]
// Exit 0 when the flight process answered at least PAIRS pairs, 1 otherwise.
#include <lcm/lcm.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "block_texture.hpp"
#include "swf/testing/stereo_frame.hpp"
#include "swf_msgs/imu_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace {

constexpr int kDisparityPx = 8;
constexpr std::int64_t kPeriodUs = 100000;

std::int64_t NowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The samples stamped in (from_us, to_us], 5 ms apart on the 5 ms grid.
void PublishImu(lcm_t* lcm, const char* channel, std::int64_t from_us, std::int64_t to_us,
                std::int64_t* seq, std::vector<std::uint8_t>* bytes) {
  constexpr std::int64_t kImuPeriodUs = 5000;
  swf_msgs::imu_t m{};
  m.specific_force_mps2[1] = -9.81;  // gravity's reaction, up = -y for a level camera
  m.flags = swf_msgs::imu_t::FLAG_VALID;
  for (std::int64_t t = (from_us / kImuPeriodUs + 1) * kImuPeriodUs; t <= to_us;
       t += kImuPeriodUs) {
    m.utime = t;
    m.seq = (*seq)++;
    bytes->resize(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(bytes->data(), 0, static_cast<int>(bytes->size()));
    lcm_publish(lcm, channel, bytes->data(), static_cast<unsigned>(bytes->size()));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 7) {
    std::fprintf(stderr,
                 "usage: %s URL CHANNEL NAV_CHANNEL WIDTH HEIGHT PAIRS [--junk] [--imu CHANNEL]\n",
                 argv[0]);
    return 2;
  }
  const char* channel = argv[2];
  const int width = std::atoi(argv[4]);
  const int height = std::atoi(argv[5]);
  const int pairs = std::atoi(argv[6]);
  bool junk = false;
  const char* imu_channel = nullptr;
  for (int i = 7; i < argc; ++i) {
    if (std::strcmp(argv[i], "--junk") == 0) {
      junk = true;
    } else if (std::strcmp(argv[i], "--imu") == 0 && i + 1 < argc) {
      imu_channel = argv[++i];
    } else {
      std::fprintf(stderr, "lcm_stereo_publisher: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  const int slide = imu_channel != nullptr ? 0 : 1;  // pixels per frame
  lcm_t* lcm = lcm_create(argv[1]);
  if (lcm == nullptr) return 1;
  // The flight process's answers: how many, and when the last came.
  struct Answers {
    int count = 0;
    std::int64_t last_us = 0;
  } answers;
  lcm_subscribe(
      lcm, argv[3],
      [](const lcm_recv_buf_t*, const char*, void* a) {
        Answers* answers = static_cast<Answers*>(a);
        ++answers->count;
        answers->last_us = NowUs();
      },
      &answers);
  swf_msgs::stereo_frame_t f = swf::testing::RawStereoFrame(width, height);
  std::vector<std::uint8_t> bytes;
  std::int64_t next_us = NowUs();
  bool junk_sent = false;
  std::int64_t imu_seq = 0;
  std::int64_t imu_until_us = 0;  // the last IMU stamp published
  // Until the flight process has stopped answering (1 s of silence after its first answer).
  for (int k = 0; k < 600 && !(answers.count > 0 && NowUs() - answers.last_us > 1000000); ++k) {
    if (junk && !junk_sent && answers.count > 0) {
      // Once the flight process is known to listen (it answered a frame).
      const std::uint8_t bytes[5] = {1, 2, 3, 4, 5};
      lcm_publish(lcm, channel, bytes, sizeof bytes);
      junk_sent = true;
    }
    f.seq = k;
    const std::int64_t exposure_us = NowUs();
    if (imu_channel != nullptr) {
      PublishImu(lcm, imu_channel, k == 0 ? exposure_us - kPeriodUs : imu_until_us, exposure_us,
                 &imu_seq, &bytes);
      imu_until_us = exposure_us;
    }
    f.left_exposure_utime = exposure_us;
    f.right_exposure_utime = f.left_exposure_utime;
    f.utime = f.left_exposure_utime;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        f.left[static_cast<std::size_t>(y * width + x)] =
            swf::testing::BlockTexture(x + slide * k, y);
        f.right[static_cast<std::size_t>(y * width + x)] =
            swf::testing::BlockTexture(x + slide * k + kDisparityPx, y);
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
  std::fprintf(stderr, "lcm_stereo_publisher: %d nav_state_t seen, %d wanted\n", answers.count,
               pairs);
  lcm_destroy(lcm);
  return answers.count >= pairs ? 0 : 1;
}
