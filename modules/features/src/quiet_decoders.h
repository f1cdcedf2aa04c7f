#pragma once
/*
  quiet_decoders.h: the image and video decoders kept from printing (the library never prints):
  C's standard error (file descriptor 2: libpng, libjpeg, FFmpeg and GStreamer print there) sent to
  /dev/null, and C++'s std::cout, std::cerr and std::clog to nowhere (ViSP's vpVideoReader prints
  "Warning: Unable to decode image N" on std::cout). Private to yawdepth::features.
*/
#include <cstdio>
#include <fcntl.h>
#include <iostream>
#include <mutex>
#include <streambuf>
#include <unistd.h>

namespace yawdepth {
namespace detail {

/*! \brief While alive: holds a process-wide lock, points file descriptor 2 at /dev/null and the C++
    standard streams at nothing (what any thread writes there meanwhile is lost too); all comes
    back at the end of scope. Not nested: one at a time per thread. */
class QuietDecoders {
public:
  QuietDecoders()
      : lock_(mutex()), cout_(std::cout.rdbuf(&nullBuf())), cerr_(std::cerr.rdbuf(&nullBuf())),
        clog_(std::clog.rdbuf(&nullBuf()))
  {
    std::fflush(stderr);
    const int null_fd = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (null_fd < 0)
      return;
    saved_ = ::dup(STDERR_FILENO);
    if (saved_ >= 0 && ::dup2(null_fd, STDERR_FILENO) < 0) {
      ::close(saved_);
      saved_ = -1;
    }
    ::close(null_fd);
  }
  ~QuietDecoders()
  {
    if (saved_ >= 0) {
      std::fflush(stderr);
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
    }
    std::cout.rdbuf(cout_);
    std::cerr.rdbuf(cerr_);
    std::clog.rdbuf(clog_);
  }
  QuietDecoders(const QuietDecoders &) = delete;
  QuietDecoders &operator=(const QuietDecoders &) = delete;

private:
  struct NullBuf : std::streambuf {
    int overflow(int c) override { return traits_type::not_eof(c); }
    std::streamsize xsputn(const char *, std::streamsize n) override { return n; }
  };
  static std::mutex &mutex()
  {
    static std::mutex m;
    return m;
  }
  static NullBuf &nullBuf()
  {
    static NullBuf b;
    return b;
  }
  std::lock_guard<std::mutex> lock_;
  std::streambuf *cout_, *cerr_, *clog_;
  int saved_ = -1;
};

} // namespace detail
} // namespace yawdepth
