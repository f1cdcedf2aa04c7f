// libFuzzer target: yawdepth::readTracksCsv.
#include "fuzz_common.h"

#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".csv");
  try {
    const std::vector<yawdepth::Track> tracks = yawdepth::readTracksCsv(file.write(data, size));
    for (const yawdepth::Track &t : tracks)
      for (std::size_t i = 1; i < t.observations.size(); ++i)
        if (!(t.observations[i - 1].frame < t.observations[i].frame))
          __builtin_trap(); // each track is sorted by frame, without repeats
  } catch (const yawdepth::Error &) {
  }
  return 0;
}
