// libFuzzer target: the rosbag2 .db3 reader (through SQLite, read-only) and the CDR decoders of
// every message read. The input is the file.
#include "fuzz_bag_common.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".db3");
  try {
    yawdepth_fuzz::readBag(file.write(data, size));
  } catch (const yawdepth::Error &) {
  }
  return 0;
}
