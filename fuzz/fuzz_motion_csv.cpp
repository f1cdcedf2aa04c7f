// libFuzzer target: yawdepth::readMotionCsv, with and without a fixed yaw from the rig file.
#include "fuzz_common.h"

#include <optional>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".csv");
  const std::string &path = file.write(data, size);
  for (const std::optional<double> fixed_yaw : {std::optional<double>(), std::optional<double>(1.5708)}) {
    try {
      const yawdepth::MotionLog log = yawdepth::readMotionCsv(path, fixed_yaw);
      for (const yawdepth::MotionSample &s : log.samples)
        if (log.find(s.frame) != &s)
          __builtin_trap(); // frames are strictly increasing, so each one is found at its place
    } catch (const yawdepth::Error &) {
    }
  }
  return 0;
}
