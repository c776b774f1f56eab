// The IMU over real LCM (UDP multicast; run inside a private network namespace whose only
// interface is loopback, see CMakeLists.txt): LcmImuInput receives imu_t from a publisher, the
// frame group takes the samples due by each exposure in arrival order, and what cannot be used
// (a message that does not decode, a stamp far beyond the exposure asked for) is counted.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "swf/app/lcm_io.hpp"
#include "swf_msgs/imu_t.hpp"

namespace swf::app {
namespace {

const char* Url() {
  const char* url = std::getenv("SWF_TEST_LCM_URL");
  return url != nullptr ? url : "udpm://239.255.76.67:7667?ttl=0";
}

void Publish(lcm::LCM* lcm, std::int64_t seq, std::int64_t utime) {
  swf_msgs::imu_t m{};
  m.utime = utime;
  m.seq = seq;
  m.angular_rate_radps[2] = 0.1;
  m.specific_force_mps2[2] = 9.81;
  m.flags = swf_msgs::imu_t::FLAG_VALID;
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  ASSERT_EQ(lcm->publish("SWF_IMU", buf.data(), static_cast<unsigned>(buf.size())), 0);
}

// Waits until the input has received n messages (at most 5 s).
bool WaitReceived(const LcmImuInput& in, std::int64_t n) {
  for (int i = 0; i < 500 && in.Counters().received < n; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return in.Counters().received >= n;
}

TEST(LcmImuTest, SamplesArriveInOrderAndBadOnesAreCounted) {
  LcmImuInput in;
  std::string error;
  ASSERT_TRUE(in.Start(Url(), "SWF_IMU", &error)) << error;
  lcm::LCM publisher(Url());
  ASSERT_TRUE(publisher.good());
  // Ten samples at 200 Hz from t = 1 s, a message that does not decode, a sample stamped an
  // hour later (a corrupt stamp), then the stream goes on.
  for (int k = 0; k < 10; ++k) Publish(&publisher, k, 1000000 + 5000 * k);
  const std::uint8_t junk[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(publisher.publish("SWF_IMU", junk, sizeof junk), 0);
  Publish(&publisher, 10, 1000000 + 3600000000LL);
  for (int k = 11; k < 20; ++k) Publish(&publisher, k, 1000000 + 5000 * k);
  ASSERT_TRUE(WaitReceived(in, 21));

  estimator::ImuSample<double> s;
  std::vector<std::int64_t> first;
  while (in.NextImu(1000000 + 5000 * 4, &s)) first.push_back(s.seq);  // due by the 5th sample
  EXPECT_EQ(first, (std::vector<std::int64_t>{0, 1, 2, 3, 4}));
  std::vector<std::int64_t> rest;
  while (in.NextImu(1000000 + 5000 * 19, &s)) rest.push_back(s.seq);
  EXPECT_EQ(rest, (std::vector<std::int64_t>{5, 6, 7, 8, 9, 11, 12, 13, 14, 15, 16, 17, 18, 19}));
  EXPECT_EQ(rest.back(), 19);
  in.Stop();
  const LcmImuCounters c = in.Counters();
  EXPECT_EQ(c.received, 21);
  EXPECT_EQ(c.undecodable, 1);
  EXPECT_EQ(c.future_dropped, 1);
  EXPECT_EQ(c.queue_full, 0);
}

}  // namespace
}  // namespace swf::app
