// libFuzzer target: the readers of a user's recording (yawdepth/io/recording.h): the format
// detection, TUM, EuRoC, timestamped yawdepth CSV, a ViSP vpPoseVector file, and an image list
// (TUM rgb.txt, EuRoC data.csv), each followed by the time alignment of what was read.
// The first byte picks the reader; the rest is the file.
#include "fuzz_common.h"

#include <optional>
#include <yawdepth/error.h>
#include <yawdepth/io/recording.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  if (size < 1)
    return 0;
  static const yawdepth_fuzz::TempFile file(".txt");
  const std::string &path = file.write(data + 1, size - 1);
  const int which = data[0] % 5;
  try {
    if (which <= 2) {
      static const yawdepth::MotionFormat kFormats[3] = {yawdepth::MotionFormat::Auto, yawdepth::MotionFormat::Tum,
                                                         yawdepth::MotionFormat::Euroc};
      const yawdepth::MotionLog log = yawdepth::readMotionFile({path}, kFormats[which], std::nullopt);
      if (log.timestamped) {
        if (log.times.size() != log.samples.size())
          __builtin_trap();
        for (std::size_t i = 1; i < log.times.size(); ++i)
          if (!(log.times[i] > log.times[i - 1]))
            __builtin_trap(); // times are strictly increasing
        yawdepth::ImageList images;
        images.times = {log.times.front(), 0.5 * (log.times.front() + log.times.back()), log.times.back() + 1};
        images.paths = {"a.png", "b.png", "c.png"};
        const yawdepth::TimeAlignment a =
            yawdepth::alignMotionToImages(log, images, yawdepth::TimeAlignmentOptions(), path, "images");
        if (a.matched + a.before + a.after + a.in_gap != a.images || a.log.samples.size() != a.matched)
          __builtin_trap();
        for (const yawdepth::MotionSample &s : a.log.samples)
          if (!s.position().allFinite() || !s.theta_u.allFinite())
            __builtin_trap();
      }
    } else if (which == 3) {
      yawdepth::readVispPoseFile(path);
    } else {
      yawdepth::readImageList(path, true);
    }
  } catch (const yawdepth::Error &) {
  }
  return 0;
}
