// libFuzzer target: yawdepth::readRigFile (YAML through yaml-cpp).
#include "fuzz_common.h"

#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".yaml");
  try {
    yawdepth::readRigFile(file.write(data, size));
  } catch (const yawdepth::Error &) {
  }
  return 0;
}
