// The summaries the ground tools print or write: valid JSON whatever bytes an argument held.
#include <gtest/gtest.h>

#include <string>

#include "swf/ground_cli/ground_cli.hpp"

namespace swf::ground_cli {
namespace {

// GIVEN a summary that echoes an argument which is not UTF-8 (a file name in Latin-1) WHEN it is
// printed THEN stdout holds one valid JSON document with the bytes replaced (nlohmann's dump()
// would throw) and the rest of the document as given.
TEST(GroundCli, PrintJsonReplacesBytesThatAreNotUtf8) {
  const std::string latin1_name = "caf\xe9.png";
  const nlohmann::json summary = {{"written", 3}, {"arguments", {latin1_name}}};
  ::testing::internal::CaptureStdout();
  PrintJson(summary, -1);
  const std::string out = ::testing::internal::GetCapturedStdout();
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.back(), '\n');
  const nlohmann::json back = nlohmann::json::parse(out);
  EXPECT_EQ(back["written"], 3);
  EXPECT_EQ(back["arguments"][0], "caf\xef\xbf\xbd.png");  // U+FFFD for the lone 0xe9
}

// GIVEN an ordered summary WHEN printed with an indent THEN its fields keep their order and the
// text is the indented dump the tools printed before (one newline at the end).
TEST(GroundCli, PrintJsonKeepsOrderAndIndent) {
  nlohmann::ordered_json report;
  report["z"] = 1;
  report["a"] = "x";
  ::testing::internal::CaptureStdout();
  PrintJson(report, 2);
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), report.dump(2) + "\n");
}

}  // namespace
}  // namespace swf::ground_cli
