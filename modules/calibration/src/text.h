#pragma once
/*
  Private to yawdepth::calibration: the unit and number formats its reports and messages share, and the
  jackknife's standard error.
*/
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

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

/* The delete-a-group jackknife's standard error from the estimates with each group left out in
   turn: sqrt((G - 1) / G * sum (e_g - mean)^2); 0 with fewer than two. */
inline double jackknifeSigma(const std::vector<double> &estimates)
{
  if (estimates.size() < 2)
    return 0.0;
  const double G = static_cast<double>(estimates.size());
  double mean = 0, var = 0;
  for (double e : estimates)
    mean += e / G;
  for (double e : estimates)
    var += (e - mean) * (e - mean);
  return std::sqrt(var * (G - 1) / G);
}

} // namespace calibration_detail
} // namespace yawdepth
