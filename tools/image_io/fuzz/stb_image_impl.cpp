// Compiles the stb_image decoder from Debian's libstb-dev header into the fuzz programs, so that
// libFuzzer's coverage and the sanitizers see inside it (the shared libstb.so is not
// instrumented). Its definitions take the place of the shared library's in these programs only.
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>
