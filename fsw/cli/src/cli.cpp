#include "swf/cli/cli.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>

namespace swf::cli {

std::string VersionLine(const char* tool) {
  return std::string(tool) + " " + Version() + " (commit " + Commit() + ")";
}

// ---- the parser -------------------------------------------------------------------------------

CommandLine::CommandLine(const char* tool, const char* synopsis, const char* description)
    : tool_(tool), synopsis_(synopsis), description_(description) {}

void CommandLine::Flag(const char* name, const char* help, bool* set) {
  Option o;
  o.name = name;
  o.help = help;
  o.flag = set;
  options_.push_back(o);
}

void CommandLine::Value(const char* name, const char* metavar, const char* help, std::string* value,
                        bool required) {
  Option o;
  o.name = name;
  o.metavar = metavar;
  o.help = help;
  o.required = required;
  o.value = value;
  options_.push_back(o);
}

void CommandLine::Repeated(const char* name, const char* metavar, const char* help,
                           std::vector<std::string>* values) {
  Option o;
  o.name = name;
  o.metavar = metavar;
  o.help = help;
  o.values = values;
  options_.push_back(o);
}

CommandLine::Option* CommandLine::Find(const std::string& name) {
  for (Option& o : options_) {
    if (o.name == name) return &o;
  }
  return nullptr;
}

int CommandLine::Refuse(const std::string& why) const {
  std::fprintf(stderr, "%s: %s (usage: %s --help)\n", tool_, why.c_str(), tool_);
  return kExitUsage;
}

std::string CommandLine::Help() const {
  std::string text = std::string("usage: ") + tool_ + " " + synopsis_ + "\n" + description_ + "\n";
  text += "options:\n";
  for (const Option& o : options_) {
    std::string left = "  " + o.name + (o.metavar.empty() ? "" : " " + o.metavar);
    if (left.size() < 24) left.resize(24, ' ');
    text += left + " " + o.help + (o.required ? " (required)" : "") +
            (o.values != nullptr ? " (repeatable)" : "") + "\n";
  }
  text += "  --help                   this text\n";
  text += "  --version                the version and the commit it was built from\n";
  text += "exit: 0 ok, 1 failed, 2 usage or configuration refused, 3 degraded (docs/cli.md)\n";
  return text;
}

int CommandLine::Parse(int argc, const char* const* argv) {
  arguments_.assign(argv + (argc > 0 ? 1 : 0), argv + argc);
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--help" || arg == "-h") {
      std::fputs(Help().c_str(), stdout);
      return kExitOk;
    }
    if (arg == "--version") {
      std::printf("%s\n", VersionLine(tool_).c_str());
      return kExitOk;
    }
  }
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg.rfind("--", 0) != 0) {
      return Refuse(arg.rfind('-', 0) == 0 ? "unknown option " + arg
                                           : "unexpected argument '" + arg + "'");
    }
    const std::size_t equals = arg.find('=');
    const std::string name = arg.substr(0, equals);
    Option* o = Find(name);
    if (o == nullptr) return Refuse("unknown option " + name);
    o->seen = true;
    if (o->flag != nullptr) {
      if (equals != std::string::npos) return Refuse(name + " takes no value");
      *o->flag = true;
      continue;
    }
    std::string value;
    if (equals != std::string::npos) {
      value = arg.substr(equals + 1);
    } else if (a + 1 < argc) {
      value = argv[++a];
    } else {
      return Refuse(name + " needs a value (" + o->metavar + ")");
    }
    if (o->values != nullptr) {
      o->values->push_back(value);
    } else {
      *o->value = value;
    }
  }
  for (const Option& o : options_) {
    if (o.required && !o.seen) return Refuse(o.name + " " + o.metavar + " is required");
  }
  return kContinue;
}

// ---- directories and whole files ----------------------------------------------------------------

bool MakeDirectories(const std::string& dir, std::string* error) {
  if (dir.empty()) return true;
  std::size_t end = 0;
  while (end != std::string::npos) {
    end = dir.find('/', end + 1);
    const std::string part = dir.substr(0, end);
    if (part.empty() || part == "/") continue;
    if (::mkdir(part.c_str(), 0777) == 0 || errno == EEXIST) {
      struct stat st {};
      if (::stat(part.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) continue;
      *error = "'" + part + "' exists and is not a directory";
      return false;
    }
    *error = "cannot create the directory '" + part + "': " + std::strerror(errno);
    return false;
  }
  return true;
}

bool MakeParentDirectories(const std::string& path, std::string* error) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos || slash == 0) return true;
  return MakeDirectories(path.substr(0, slash), error);
}

namespace {

// Paths the signal handler removes: written before a slot is marked in use, read only by the
// handler (unlink is async-signal-safe).
constexpr int kMaxPartialPaths = 64;
constexpr std::size_t kMaxPartialPathBytes = 1024;
struct PartialPath {
  std::atomic<bool> in_use{false};
  char path[kMaxPartialPathBytes] = "";
};
PartialPath g_partial[kMaxPartialPaths];

void RemovePartialsAndDie(int sig) {
  for (PartialPath& p : g_partial) {
    if (p.in_use.load()) ::unlink(p.path);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

int RemovePathOnSignal(const std::string& path) {
  if (path.size() >= kMaxPartialPathBytes) return -1;
  for (int i = 0; i < kMaxPartialPaths; ++i) {
    PartialPath& p = g_partial[i];
    if (p.in_use.load()) continue;
    std::memcpy(p.path, path.c_str(), path.size() + 1);
    p.in_use.store(true);
    return i;
  }
  return -1;
}

void ForgetPathOnSignal(int slot) {
  if (slot >= 0 && slot < kMaxPartialPaths) g_partial[slot].in_use.store(false);
}

void RemovePartialOutputsOnSignal() {
  struct sigaction action {};
  action.sa_handler = &RemovePartialsAndDie;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

OutputFile::~OutputFile() { Discard(); }

void OutputFile::Discard() {
  if (file_ != nullptr) std::fclose(file_);
  file_ = nullptr;
  if (!temp_path_.empty()) std::remove(temp_path_.c_str());
  ForgetPathOnSignal(slot_);
  slot_ = -1;
  temp_path_.clear();
}

bool OutputFile::Open(const std::string& path, std::string* error) {
  Discard();
  path_ = path;
  if (!MakeParentDirectories(path, error)) {
    *error = path + ": " + *error;
    return false;
  }
  temp_path_ = path + ".partial." + std::to_string(::getpid());
  slot_ = RemovePathOnSignal(temp_path_);
  file_ = std::fopen(temp_path_.c_str(), "w");
  if (file_ == nullptr) {
    *error = path + ": cannot write: " + std::strerror(errno);
    ForgetPathOnSignal(slot_);
    slot_ = -1;
    temp_path_.clear();
    return false;
  }
  return true;
}

bool OutputFile::Commit(std::string* error) {
  if (file_ == nullptr) {
    *error = path_ + ": not open";
    return false;
  }
  const bool written = std::ferror(file_) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!written || !closed) {
    *error = path_ + ": write failed: " + std::strerror(errno);
    Discard();
    return false;
  }
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    *error = path_ + ": cannot put in place: " + std::strerror(errno);
    Discard();
    return false;
  }
  ForgetPathOnSignal(slot_);
  slot_ = -1;
  temp_path_.clear();
  return true;
}

bool WriteFileAtomically(const std::string& path, const std::string& text, std::string* error) {
  OutputFile out;
  if (!out.Open(path, error)) return false;
  if (std::fwrite(text.data(), 1, text.size(), out.Stream()) != text.size()) {
    *error = path + ": write failed: " + std::strerror(errno);
    return false;
  }
  return out.Commit(error);
}

}  // namespace swf::cli
