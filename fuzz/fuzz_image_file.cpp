// libFuzzer target: yawdepth::readGrayImage (the header size check, the JPEG structure check, the
// decoders behind them).
#include "fuzz_common.h"

#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".img");
  try {
    const cv::Mat image = yawdepth::readGrayImage(file.write(data, size));
    if (image.empty() || image.type() != CV_8UC1)
      __builtin_trap(); // an image read is 8-bit gray and not empty
  } catch (const yawdepth::Error &) {
  }
  return 0;
}
