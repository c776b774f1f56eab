// The flight processes' parser answers as CLI11 does for the ground tools (docs/cli.md), and an
// OutputFile appears whole or not at all.
#include "swf/cli/cli.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <string>
#include <vector>

#include "swf/testing/files.hpp"

namespace swf::cli {
namespace {

struct Parsed {
  std::string config;
  std::vector<std::string> sets;
  bool check = false;
  int code = 0;
};

Parsed ParseOf(std::vector<const char*> args) {
  Parsed p;
  CommandLine cl("swf-test", "--config FILE [--set 'key: value']...", "A test program.");
  cl.Value("--config", "FILE", "the configuration", &p.config, true);
  cl.Repeated("--set", "'key: value'", "an override", &p.sets);
  cl.Flag("--check", "validate only", &p.check);
  args.insert(args.begin(), "swf-test");
  p.code = cl.Parse(static_cast<int>(args.size()), args.data());
  return p;
}

TEST(CommandLineTest, TakesValuesFlagsAndRepeats) {
  const Parsed p = ParseOf({"--config", "a.cfg", "--set", "x: 1", "--set=y: 2", "--check"});
  EXPECT_EQ(p.code, kContinue);
  EXPECT_EQ(p.config, "a.cfg");
  EXPECT_EQ(p.sets, (std::vector<std::string>{"x: 1", "y: 2"}));
  EXPECT_TRUE(p.check);
  EXPECT_EQ(ParseOf({"--config=b.cfg"}).config, "b.cfg");
}

TEST(CommandLineTest, HelpAndVersionExitZero) {
  EXPECT_EQ(ParseOf({"--help"}).code, kExitOk);
  EXPECT_EQ(ParseOf({"--config", "a", "-h"}).code, kExitOk);
  EXPECT_EQ(ParseOf({"--version"}).code, kExitOk);
}

TEST(CommandLineTest, RefusesWhatItDoesNotKnowWithUsageExit) {
  EXPECT_EQ(ParseOf({"--config", "a", "--bogus"}).code, kExitUsage);
  EXPECT_EQ(ParseOf({"--config", "a", "-x"}).code, kExitUsage);
  EXPECT_EQ(ParseOf({"--config", "a", "stray"}).code, kExitUsage);
  EXPECT_EQ(ParseOf({"--config"}).code, kExitUsage);       // missing value
  EXPECT_EQ(ParseOf({"--set", "x: 1"}).code, kExitUsage);  // missing required option
  EXPECT_EQ(ParseOf({"--config", "a", "--check=yes"}).code, kExitUsage);
}

TEST(VersionTest, NamesVersionAndCommit) {
  const std::string line = VersionLine("swf-test");
  EXPECT_EQ(line.rfind("swf-test ", 0), 0u) << line;
  EXPECT_NE(line.find(Version()), std::string::npos);
  EXPECT_NE(line.find(std::string("(commit ") + Commit() + ")"), std::string::npos) << line;
  EXPECT_GT(std::string(Commit()).size(), 0u);
}

using swf::testing::Exists;
using swf::testing::ReadText;
using swf::testing::ScratchDir;

TEST(OutputFileTest, AppearsOnlyWhenCommittedInDirectoriesItCreates) {
  ScratchDir dir;
  const std::string path = dir.Path() + "/a/b/summary.json";
  std::string error;
  {
    OutputFile out;
    ASSERT_TRUE(out.Open(path, &error)) << error;
    std::fputs("{\"half\":", out.Stream());
    std::fflush(out.Stream());
    EXPECT_FALSE(Exists(path));  // only the temporary exists while writing
  }
  EXPECT_FALSE(Exists(path));  // dropped without Commit: nothing left
  EXPECT_TRUE(Exists(dir.Path() + "/a/b"));
  ASSERT_TRUE(WriteFileAtomically(path, "{}\n", &error)) << error;
  EXPECT_EQ(ReadText(path), "{}\n");
  // Nothing but the committed file in the directory.
  EXPECT_EQ(std::system(("test $(ls -A '" + dir.Path() + "/a/b' | wc -l) -eq 1").c_str()), 0);
}

TEST(OutputFileTest, RefusesAPathUnderAFile) {
  ScratchDir dir;
  std::string error;
  ASSERT_TRUE(WriteFileAtomically(dir.Path() + "/file", "x", &error)) << error;
  EXPECT_FALSE(WriteFileAtomically(dir.Path() + "/file/sub/out.json", "{}", &error));
  EXPECT_NE(error.find("is not a directory"), std::string::npos) << error;
}

TEST(OutputFileTest, ASignalRemovesThePartialFile) {
  ScratchDir dir;
  const std::string path = dir.Path() + "/out.json";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    RemovePartialOutputsOnSignal();
    OutputFile out;
    std::string error;
    if (!out.Open(path, &error)) ::_exit(10);
    std::fputs("{\"half\":", out.Stream());
    std::fflush(out.Stream());
    std::raise(SIGTERM);
    ::_exit(11);  // not reached
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit " << WEXITSTATUS(status);
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_EQ(std::system(("test -z \"$(ls -A '" + dir.Path() + "')\"").c_str()), 0)
      << "a partial file was left behind";
}

}  // namespace
}  // namespace swf::cli
