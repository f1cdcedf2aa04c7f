#include <yawdepth/camera/quiet_visp.h>

#include <iostream>
#include <streambuf>

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

QuietVisp::QuietVisp()
    : lock_(quietMutex()), cout_(std::cout.rdbuf(&nullBuf())), cerr_(std::cerr.rdbuf(&nullBuf())),
      clog_(std::clog.rdbuf(&nullBuf()))
{
}

QuietVisp::~QuietVisp()
{
  std::cout.rdbuf(cout_);
  std::cerr.rdbuf(cerr_);
  std::clog.rdbuf(clog_);
}

} // namespace detail
} // namespace yawdepth
