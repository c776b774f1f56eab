// The command-line convention every swf-* program follows (docs/cli.md), in the part the flight
// processes can carry: the build's version and commit, the exit codes, a small option parser
// (swf-fsw, swf-sil and swf-replay; the ground tools use CLI11 through tools/ground_cli, which
// answers the same way), and output files that appear whole or not at all.
//
// Standard library and POSIX only: no exceptions, no RTTI. Everything here runs before a flight
// process starts or after it stops (it allocates).
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace swf::cli {

// Exit codes (docs/cli.md, one table for every program).
inline constexpr int kExitOk = 0;        // done, nothing to report against the result
inline constexpr int kExitFailed = 1;    // could not do the job, or the result judged failed
inline constexpr int kExitUsage = 2;     // command line or configuration refused: nothing ran
inline constexpr int kExitDegraded = 3;  // done, with reservations the summary names
// Parse()'s answer when the program goes on.
inline constexpr int kContinue = -1;

// The project's version (CMake's project(VERSION)) and the git commit the build was made from:
// 12 hex digits, "-dirty" when the tree had uncommitted changes, "unknown" outside a git checkout
// (or SWF_COMMIT from the environment when configuring from a source archive). Both come from
// one small generated file (cmake/swf_commit.cmake) that changes only when the commit does.
const char* Version();
const char* Commit();
// "swf-fsw 0.1.0 (commit 4160ad9c1b2a)": what --version prints.
std::string VersionLine(const char* tool);

// A parser for long options: `--name VALUE`, `--name=VALUE`, `--flag`. --help / -h prints the
// usage on stdout and --version the version line (exit 0); an unknown option, a positional
// argument, a missing value, a flag given a value or a missing required option is refused with
// one line naming it and a pointer to --help (exit 2).
class CommandLine {
 public:
  // `synopsis`: the usage line after the program's name; `description`: what it does.
  CommandLine(const char* tool, const char* synopsis, const char* description);

  void Flag(const char* name, const char* help, bool* set);
  void Value(const char* name, const char* metavar, const char* help, std::string* value,
             bool required = false);
  // May be given any number of times; the values in order.
  void Repeated(const char* name, const char* metavar, const char* help,
                std::vector<std::string>* values);

  // kContinue, or the exit code (kExitOk after --help / --version, kExitUsage when refused).
  int Parse(int argc, const char* const* argv);
  std::string Help() const;
  // The arguments as given, for the summary's echo of the command line.
  const std::vector<std::string>& Arguments() const { return arguments_; }

 private:
  struct Option {
    std::string name;
    std::string metavar;  // empty: a flag
    std::string help;
    bool required = false;
    bool seen = false;
    bool* flag = nullptr;
    std::string* value = nullptr;
    std::vector<std::string>* values = nullptr;
  };
  Option* Find(const std::string& name);
  int Refuse(const std::string& why) const;

  const char* tool_;
  std::string synopsis_;
  std::string description_;
  std::vector<Option> options_;
  std::vector<std::string> arguments_;
};

// Creates `dir` and its missing parents (mode 0777 before umask). True when it exists as a
// directory afterwards; otherwise `error` names the component that failed and why.
bool MakeDirectories(const std::string& dir, std::string* error);
// MakeDirectories for the directory of a file path ("" and "." need nothing).
bool MakeParentDirectories(const std::string& path, std::string* error);

// A file written under a temporary name beside its final one ("<path>.partial.<pid>") and renamed
// into place by Commit(), so a reader never sees it half written. Never committed (an error, an
// early return) it is removed; with RemovePartialOutputsOnSignal() installed it is removed when
// SIGINT or SIGTERM ends the program too. Open() creates the missing directories.
class OutputFile {
 public:
  OutputFile() = default;
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  bool Open(const std::string& path, std::string* error);
  std::FILE* Stream() { return file_; }
  // Flushes, closes and renames; false (and the temporary removed) on any write error.
  bool Commit(std::string* error);
  const std::string& Path() const { return path_; }

 private:
  void Discard();
  std::FILE* file_ = nullptr;
  std::string path_;
  std::string temp_path_;
  int slot_ = -1;  // in the signal handler's table
};

// `text` into `path` through an OutputFile.
bool WriteFileAtomically(const std::string& path, const std::string& text, std::string* error);

// SIGINT and SIGTERM remove every OutputFile not yet committed (and every path given to
// RemovePathOnSignal), then end the program as the signal would have (exit status 128 + signal).
// For programs that have no orderly stop of their own; the flight processes stop their rate
// groups on those signals and finish their files instead.
void RemovePartialOutputsOnSignal();
// A file this program writes in place (a library's writer that takes a path): removed by the
// handler until ForgetPathOnSignal(slot). -1 when the table (64 entries) is full.
int RemovePathOnSignal(const std::string& path);
void ForgetPathOnSignal(int slot);

}  // namespace swf::cli
