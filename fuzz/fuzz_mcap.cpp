// libFuzzer target: the MCAP reader (records, chunks: none, zstd, lz4; summary, statistics) and the
// CDR decoders of every message read. The input is the file after its 8-byte magic.
#include "fuzz_bag_common.h"
#include "fuzz_common.h"

#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".mcap");
  static const std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  std::vector<std::uint8_t> bytes(kMagic, kMagic + 8);
  bytes.insert(bytes.end(), data, data + size);
  try {
    yawdepth_fuzz::readBag(file.write(bytes.data(), bytes.size()));
  } catch (const yawdepth::Error &) {
  }
  return 0;
}
