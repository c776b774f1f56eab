// Fuzz entry point for reading LCM logs (swf/drivers/log_stereo_source.hpp): the input is the whole
// log file. No input may crash, throw or allocate past the stated limits; the frames loaded are
// served with strictly increasing sequence numbers and advancing exposure times, each image the
// size the log states; a load that stops early names the record.
#include <cstddef>
#include <cstdint>
#include <string>

#include "swf/drivers/log_stereo_source.hpp"

namespace {

void Expect(bool condition) {
  if (!condition) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace swf;
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  drivers::LogReader reader;
  reader.OpenBytes(bytes, "fuzz.lcmlog");
  drivers::LogStereoSource source;
  source.Load(&reader, "SWF_STEREO");
  Expect(source.LoadError().empty() || source.LoadError().rfind("fuzz.lcmlog: record ", 0) == 0);
  Expect(source.Start() == core::Status::kOk);
  drivers::StereoPair pair;
  std::size_t served = 0;
  std::int64_t last_seq = -1;
  core::TimeNs last_ns = -1;
  while (source.Next(0, &pair) == core::Status::kOk) {
    ++served;
    Expect(static_cast<std::int64_t>(pair.seq) > last_seq && pair.left_exposure_ns > last_ns);
    Expect(pair.left.width == source.Width() && pair.left.height == source.Height());
    Expect(pair.left.width > 0 && pair.left.height > 0 && pair.left.data != nullptr);
    const std::size_t n = static_cast<std::size_t>(pair.left.width) * pair.left.height;
    // Both images readable to their last byte (AddressSanitizer checks the reads).
    const volatile std::uint8_t last_bytes = pair.left.data[n - 1] ^ pair.right.data[n - 1];
    (void)last_bytes;
    drivers::MotionInput motion;
    (void)source.Motion(pair.seq, &motion);
    last_seq = static_cast<std::int64_t>(pair.seq);
    last_ns = pair.left_exposure_ns;
  }
  Expect(served == source.NumFrames());
  Expect(source.Stats().frames_rejected ==
         static_cast<std::uint64_t>(source.StreamStats().Refused()));
  return 0;
}
