#include "swf/core/status.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "swf/core/assert.hpp"

namespace swf::core {
namespace {

TEST(Status, EveryValueHasADistinctName) {
  const Status all[] = {Status::kOk,
                        Status::kInvalidArgument,
                        Status::kNotConfigured,
                        Status::kFull,
                        Status::kEmpty,
                        Status::kTimeout,
                        Status::kNotConverged,
                        Status::kNumericalFailure,
                        Status::kCorruptData,
                        Status::kIoError,
                        Status::kDeviceLost,
                        Status::kUnsupported};
  for (std::size_t i = 0; i < std::size(all); ++i) {
    ASSERT_NE(ToString(all[i]), nullptr);
    EXPECT_STRNE(ToString(all[i]), "unknown status");
    for (std::size_t j = 0; j < i; ++j) EXPECT_STRNE(ToString(all[i]), ToString(all[j]));
  }
  EXPECT_TRUE(IsOk(Status::kOk));
  EXPECT_FALSE(IsOk(Status::kFull));
}

int g_failures = 0;
int g_failed_line = 0;
void RecordingHandler(const char*, const char*, int line) {
  ++g_failures;
  g_failed_line = line;
}

TEST(Assert, ReplaceableHandlerSeesTheFailureAndDefaultIsRestored) {
  g_failures = 0;
  const AssertHandler previous = SetAssertHandler(&RecordingHandler);
  SWF_ASSERT(1 + 1 == 2);
  EXPECT_EQ(g_failures, 0);
  const int line = __LINE__ + 1;
  SWF_ASSERT(1 + 1 == 3);
  EXPECT_EQ(g_failures, 1);
  EXPECT_EQ(g_failed_line, line);
  EXPECT_EQ(SetAssertHandler(previous), &RecordingHandler);
}

TEST(AssertDeathTest, DefaultHandlerAborts) {
  EXPECT_DEATH(SWF_ASSERT(false), "SWF_ASSERT failed: false");
}

}  // namespace
}  // namespace swf::core
