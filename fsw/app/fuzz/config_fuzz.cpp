// Fuzz entry point for the configuration parser (swf/app/config.hpp): the input is the file's
// text, parsed as the flight binary reads it and as swf-sil does (with the simulator's keys,
// tools/sil). No input may crash or throw; a refusal names the file and quotes at most a bounded
// excerpt of what it read (never the input whole, never a control byte).
#include <cstddef>
#include <cstdint>
#include <string>

#include "swf/app/config.hpp"
#include "swf/sil/sil.hpp"

namespace {

void Expect(bool condition) {
  if (!condition) __builtin_trap();
}

// Field names, the file name, the limits and one excerpt of at most 48 bytes fit in this.
constexpr std::size_t kMaxErrorBytes = 1024;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (const swf::app::ConfigExtension* keys :
       {static_cast<const swf::app::ConfigExtension*>(nullptr), swf::sil::SimConfigExtension()}) {
    swf::app::FswConfig config;
    std::string error;
    if (!swf::app::ParseConfig(text, "fuzz.cfg", &config, &error, keys)) {
      Expect(error.rfind("fuzz.cfg", 0) == 0);
      Expect(error.size() <= kMaxErrorBytes);
      for (const char ch : error) {
        const auto c = static_cast<unsigned char>(ch);
        Expect(c >= 0x20 && c < 0x7f);  // printable ASCII: other bytes are escaped
      }
    }
  }
  return 0;
}
