#include "gnuplot_job.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "swf/plot/plot.hpp"

extern char** environ;

namespace swf::plot {

namespace {

std::string TempRoot() {
  const char* tmp = std::getenv("TMPDIR");
  return tmp != nullptr && *tmp != '\0' ? tmp : "/tmp";
}

// gnuplot's diagnostics without its echo of the script line: the lines that say what went wrong,
// joined, at most a few hundred characters.
std::string Diagnostics(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::string text;
  while (std::getline(in, line) && text.size() < 300) {
    if (line.find_first_not_of(" \t^") == std::string::npos) continue;
    if (line.find("\"plot.gp\"") != std::string::npos || line.find("line ") != std::string::npos ||
        line.find("rror") != std::string::npos || line.find("arning") != std::string::npos) {
      text += (text.empty() ? "" : " / ") + line.substr(line.find_first_not_of(' '));
    }
  }
  return text.empty() ? "no message" : text;
}

}  // namespace

std::string GnuplotProgram() {
  const char* program = std::getenv("SWF_GNUPLOT");
  return program != nullptr && *program != '\0' ? program : "gnuplot";
}

std::string Quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string TitleQuoted(const std::string& text, int width_px, int font_pt) {
  // Sans at the title's size averages 0.69 of the font size per character (a 90-character title
  // at 12 spans 744 px); 0.75 leaves room for wide letters, 0.9 of the width for the margins.
  const std::size_t per_line =
      std::max<std::size_t>(8, static_cast<std::size_t>(0.9 * width_px / (0.75 * font_pt)));
  std::vector<std::string> lines(1);
  std::string word;
  for (std::istringstream words(text); words >> word;) {
    while (word.size() > per_line) {  // a word longer than a line is cut where a line ends
      if (!lines.back().empty()) lines.emplace_back();
      std::size_t cut = per_line;
      while (cut > 1 && (static_cast<unsigned char>(word[cut]) & 0xC0) == 0x80) --cut;  // UTF-8
      lines.back() = word.substr(0, cut);
      word.erase(0, cut);
      lines.emplace_back();
    }
    if (!lines.back().empty() && lines.back().size() + 1 + word.size() > per_line)
      lines.emplace_back();
    lines.back() += (lines.back().empty() ? "" : " ") + word;
  }
  if (lines.size() > 1 && lines.back().empty()) lines.pop_back();
  std::string out = "\"";
  for (std::size_t k = 0; k < lines.size(); ++k) {
    if (k > 0) out += "\\n";
    for (char c : lines[k]) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
  }
  return out + "\"";
}

std::string Number(double v) {
  if (!std::isfinite(v)) return "NaN";
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

GnuplotJob::GnuplotJob(int width_px, int height_px) : width_px_(width_px), height_px_(height_px) {
  std::string pattern = TempRoot() + "/swf-plot-XXXXXX";
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  if (mkdtemp(buffer.data()) == nullptr) {
    error_ = "cannot create a temporary directory in " + TempRoot() + ": " + std::strerror(errno);
    return;
  }
  dir_ = buffer.data();
}

GnuplotJob::~GnuplotJob() {
  if (dir_.empty()) return;
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

std::string GnuplotJob::Write(const std::string& name, const void* bytes, std::size_t size) {
  const std::string path = dir_ + "/" + name;
  if (dir_.empty()) return Quoted(path);
  std::ofstream out(path, std::ios::binary);
  out.write(static_cast<const char*>(bytes), static_cast<std::streamsize>(size));
  if (!out && error_.empty()) error_ = "cannot write the plot's data " + path;
  return Quoted(path);
}

std::string GnuplotJob::Data(const std::string& name, const std::string& text) {
  return Write(name, text.data(), text.size());
}

std::string GnuplotJob::Binary(const std::string& name, const void* bytes, std::size_t size) {
  return Write(name, bytes, size);
}

bool GnuplotJob::Render(const std::string& script, const std::string& png, std::string* error) {
  const auto fail = [&](const std::string& why) {
    *error = png + ": " + why;
    return false;
  };
  if (!error_.empty()) return fail(error_);
  const std::string image = dir_ + "/plot.png";
  std::ostringstream head;
  head << "set encoding utf8\nset terminal pngcairo size " << width_px_ << "," << height_px_
       << " noenhanced font 'Sans,10'\nset output " << Quoted(image) << "\n";
  const std::string script_path = dir_ + "/plot.gp";
  const bool ends_line = script.empty() || script.back() == '\n';
  Data("plot.gp", head.str() + script + (ends_line ? "" : "\n") + "unset output\n");
  if (!error_.empty()) return fail(error_);

  const std::string program = GnuplotProgram();
  const std::string log = dir_ + "/gnuplot.log";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<char*> argv = {const_cast<char*>(program.c_str()),
                             const_cast<char*>(script_path.c_str()), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    return fail("cannot run " + program + ": " + std::strerror(spawned) +
                " (install gnuplot-nox, or name the program in SWF_GNUPLOT)");
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return fail("cannot wait for " + program + ": " + std::strerror(errno));
  }
  if (WIFSIGNALED(status)) {
    return fail(program + " was killed by signal " + std::to_string(WTERMSIG(status)));
  }
  if (WEXITSTATUS(status) != 0) {
    return fail(program + " exited with status " + std::to_string(WEXITSTATUS(status)) + ": " +
                Diagnostics(log));
  }
  std::error_code ec;
  if (std::filesystem::file_size(image, ec) == 0 || ec) {
    return fail(program + " exited with status 0 but drew no image");
  }
  std::filesystem::copy_file(image, png, std::filesystem::copy_options::overwrite_existing, ec);
  if (ec) return fail("cannot write the PNG: " + ec.message());
  return true;
}

}  // namespace swf::plot
