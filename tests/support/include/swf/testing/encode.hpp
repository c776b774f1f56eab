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

}  // namespace swf::testing
