// A message's encoded bytes as lcm-gen's encode() writes them, for tests that publish or record
// raw bytes (often altered afterwards to make a malformed message). A failed encode fails the
// calling test.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace swf::testing {

template <typename Msg>
std::vector<std::uint8_t> Encode(const Msg& msg) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  EXPECT_EQ(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

// `bytes` with the big-endian int32 at `offset` (counted from the start, fingerprint included)
// overwritten: a length or count field set to what a hostile or broken sender might write.
inline std::vector<std::uint8_t> WithInt32(std::vector<std::uint8_t> bytes, std::size_t offset,
                                           std::int32_t value) {
  const auto u = static_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i) bytes[offset + i] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
  return bytes;
}

}  // namespace swf::testing
