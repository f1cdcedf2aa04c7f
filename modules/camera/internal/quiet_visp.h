#pragma once
/*
  quiet_visp.h: run ViSP calls that print without printing (the library never prints). Internal,
  not installed: QuietVisp is compiled into yawdepth::camera (src/quiet_visp.cpp), which uses it
  around vpXmlParserCamera; yawdepth::calibration uses it around vpCalibration, vpHandEyeCalibration
  and vpXmlParserCamera's save. Both reach this header through the yawdepth_quiet_visp_internal
  target (modules/camera/CMakeLists.txt).
*/
#include <iosfwd>
#include <mutex>

namespace yawdepth {
namespace detail {

/*
  While alive: holds a process-wide lock and sends std::cout, std::cerr and std::clog to
  nowhere. vpXmlParserCamera::parse/save print "Found camera with name ..." and vpCalibration
  prints its iterations; yawdepth wraps those calls in one QuietVisp. The lock serialises
  yawdepth's own ViSP calls (and vpCalibration's static gain); other threads that print through
  the standard streams meanwhile are silenced too.
*/
class QuietVisp {
public:
  /* Take the lock, then silence the standard streams; with `c_stdout`, also C's standard
      output (file descriptor 1: vpHandEyeCalibration prints with printf). */
  explicit QuietVisp(bool c_stdout = false);
  /* Restore the standard streams, then release the lock. */
  ~QuietVisp();
  QuietVisp(const QuietVisp &) = delete;
  QuietVisp &operator=(const QuietVisp &) = delete;

private:
  std::unique_lock<std::mutex> lock_;
  std::streambuf *cout_, *cerr_, *clog_;
  int saved_stdout_ = -1;
};

} // namespace detail
} // namespace yawdepth
