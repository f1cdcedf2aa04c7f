#pragma once
/*!
  \file fuzz_common.h
  \brief Shared by the libFuzzer targets: the parsers read files, so each input is written to a
  per-process temporary file first. A parser may reject its input only with yawdepth::Error;
  any other exception escapes LLVMFuzzerTestOneInput and aborts (a crash for libFuzzer), as
  does any sanitizer report.
*/
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>

namespace yawdepth_fuzz {

/*! \brief A file in the temporary folder, unique to this process, removed at exit. */
class TempFile {
public:
  explicit TempFile(const std::string &suffix) {
    const char *dir = std::getenv("TMPDIR");
    path_ = std::string(dir && *dir ? dir : "/tmp") + "/yawdepth_fuzz_" + std::to_string(::getpid()) + suffix;
  }
  ~TempFile() { std::remove(path_.c_str()); }
  TempFile(const TempFile &) = delete;
  TempFile &operator=(const TempFile &) = delete;

  /*! \brief Replace the file's content with `size` bytes at `data`; returns the path. */
  const std::string &write(const std::uint8_t *data, std::size_t size) const {
    std::FILE *f = std::fopen(path_.c_str(), "wb");
    if (!f)
      std::abort();
    if (size && std::fwrite(data, 1, size, f) != size)
      std::abort();
    if (std::fclose(f) != 0)
      std::abort();
    return path_;
  }

private:
  std::string path_;
};

} // namespace yawdepth_fuzz
