#include "quiet_visp.h"

#include <cstdio>
#include <fcntl.h>
#include <iostream>
#include <streambuf>
#include <unistd.h>

namespace yawdepth {
namespace detail {

namespace {

struct NullBuf : std::streambuf {
  int overflow(int c) override { return traits_type::not_eof(c); }
  std::streamsize xsputn(const char *, std::streamsize n) override { return n; }
};

std::mutex &quietMutex()
{
  static std::mutex m;
  return m;
}

NullBuf &nullBuf()
{
  static NullBuf b;
  return b;
}

} // namespace

QuietVisp::QuietVisp(bool c_stdout)
    : lock_(quietMutex()), cout_(std::cout.rdbuf(&nullBuf())), cerr_(std::cerr.rdbuf(&nullBuf())),
      clog_(std::clog.rdbuf(&nullBuf()))
{
  if (!c_stdout)
    return;
  std::fflush(stdout);
  const int null_fd = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (null_fd < 0)
    return;
  saved_stdout_ = ::dup(1);
  if (saved_stdout_ >= 0 && ::dup2(null_fd, 1) < 0) {
    ::close(saved_stdout_);
    saved_stdout_ = -1;
  }
  ::close(null_fd);
}

QuietVisp::~QuietVisp()
{
  if (saved_stdout_ >= 0) {
    std::fflush(stdout);
    ::dup2(saved_stdout_, 1);
    ::close(saved_stdout_);
  }
  std::cout.rdbuf(cout_);
  std::cerr.rdbuf(cerr_);
  std::clog.rdbuf(clog_);
}

} // namespace detail
} // namespace yawdepth
