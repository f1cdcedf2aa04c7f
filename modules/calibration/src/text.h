#pragma once
/*
  Private to yawdepth::calibration: the unit and number formats its reports and messages share.
*/
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

namespace yawdepth {
namespace calibration_detail {

constexpr double kDeg = M_PI / 180.0; //!< one degree in radians

/* v with `precision` digits after the point (reports, messages). */
inline std::string fixed(double v, int precision = 3)
{
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(precision);
  s << v;
  return s.str();
}

/* v with every digit a double holds (files that are read back). */
inline std::string num(double v)
{
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

} // namespace calibration_detail
} // namespace yawdepth
