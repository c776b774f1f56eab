// Replays fuzz inputs through a libFuzzer entry point without libFuzzer: the regression half of
// every fuzz target. ctest runs each target over its committed corpus (seeds and former crashers)
// with the ordinary compiler; `tools/run fuzz` builds the same entry point with clang's
// -fsanitize=fuzzer to search for new inputs.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

// Corpus files are small by construction; a larger file is a mistake in the corpus, not an input.
constexpr std::uintmax_t kMaxInputBytes = 16u << 20;

bool ReplayFile(const std::filesystem::path& path) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || size > kMaxInputBytes) {
    std::fprintf(stderr, "fuzz replay: %s: unreadable or larger than %ju bytes\n", path.c_str(),
                 kMaxInputBytes);
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
  LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  int inputs = 0;
  bool ok = true;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path arg(argv[i]);
    if (std::filesystem::is_directory(arg)) {
      std::vector<std::filesystem::path> files;
      for (const auto& entry : std::filesystem::directory_iterator(arg)) {
        if (entry.is_regular_file()) files.push_back(entry.path());
      }
      std::sort(files.begin(), files.end());  // deterministic order
      for (const auto& file : files) {
        ok = ReplayFile(file) && ok;
        ++inputs;
      }
    } else {
      ok = ReplayFile(arg) && ok;
      ++inputs;
    }
  }
  std::printf("fuzz replay: %d inputs, %s\n", inputs, ok ? "all ran" : "some unreadable");
  return ok && inputs > 0 ? 0 : 1;
}
