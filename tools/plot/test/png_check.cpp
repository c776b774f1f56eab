// png_check: the shell tests' check of drawn plots (png_check.hpp): every PNG named decodes, is at
// least MIN_W x MIN_H px and is not blank. Prints one line per file; exit 1 on any failure.
//   png_check MIN_W MIN_H FILE.png...
#include <cstdio>
#include <cstdlib>

#include "png_check.hpp"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: png_check MIN_W MIN_H FILE.png...\n");
    return 2;
  }
  const int min_w = std::atoi(argv[1]);
  const int min_h = std::atoi(argv[2]);
  int failed = 0;
  for (int a = 3; a < argc; ++a) {
    const swf::plot::test::PngStats s = swf::plot::test::StatsOf(argv[a]);
    const bool ok = s.decoded && s.width >= min_w && s.height >= min_h && s.gray_stddev > 5.0;
    std::printf("%s %s: %dx%d px, grey stddev %.1f%s%s\n", ok ? "ok" : "FAILED", argv[a], s.width,
                s.height, s.gray_stddev, s.decoded ? "" : ", ", s.error.c_str());
    failed += ok ? 0 : 1;
  }
  return failed == 0 ? 0 : 1;
}
