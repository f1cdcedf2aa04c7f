// cameraFromCameraInfo and sameCalibration (bag/messages.h): a ROS camera_info as yawdepth's camera,
// for import-bag and the ROS node.
#include <yawdepth/bag/messages.h>

#include <cmath>
#include <string>
#include <vector>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>

namespace yawdepth {

CameraModel cameraFromCameraInfo(const CameraInfoMessage &info, const std::string &topic)
{
  const std::string what = topic + ": camera_info";
  bool zero = true;
  for (double k : info.K)
    zero = zero && k == 0.0;
  if (zero)
    throw Error(what + " has no calibration (K is all zero)");
  for (double k : info.K)
    if (!std::isfinite(k))
      throw Error(what + " has a K that is not finite");
  const double fx = info.K[0], fy = info.K[4], cx = info.K[2], cy = info.K[5];
  const std::string &m = info.distortion_model;
  CameraModel cam;
  try {
    if (m == "plumb_bob" || (m.empty() && info.D.size() <= 5) || m == "rational_polynomial") {
      std::vector<double> d = info.D;
      while (d.size() > 5 && m == "plumb_bob" && d.back() == 0.0)
        d.pop_back();
      if (m == "rational_polynomial" && d.size() > 8) // k1 k2 p1 p2 k3 k4 k5 k6, then thin prism: must be 0
        for (std::size_t i = 8; i < d.size(); ++i)
          if (d[i] != 0.0)
            throw Error(what + ": rational_polynomial with " + std::to_string(d.size()) +
                        " coefficients (thin prism terms are not modelled)");
      if (d.size() > 8)
        d.resize(8);
      bool all_zero = true;
      for (double v : d)
        all_zero = all_zero && v == 0.0;
      if (all_zero)
        d.clear();
      else if (d.size() == 1 || d.size() == 2 || d.size() == 3)
        d.resize(4, 0.0);
      else if (d.size() == 6 || d.size() == 7)
        d.resize(8, 0.0);
      cam = CameraModel::brown(fx, fy, cx, cy, d, info.width, info.height);
    } else if (m == "equidistant") {
      std::vector<double> d = info.D;
      if (d.size() != 4)
        throw Error(what + ": equidistant with " + std::to_string(d.size()) + " coefficients, not 4");
      cam = CameraModel::kannalaBrandt(fx, fy, cx, cy, d, info.width, info.height);
    } else {
      throw Error(what + ": distortion model '" + m + "' (import-bag reads plumb_bob, rational_polynomial, equidistant)");
    }
  } catch (const Error &e) {
    const std::string w = e.what();
    if (w.rfind(topic, 0) == 0)
      throw;
    throw Error(what + ": " + w);
  }
  checkCameraPlausible(cam, what);
  return cam;
}

bool sameCalibration(const CameraInfoMessage &a, const CameraInfoMessage &b)
{
  return a.width == b.width && a.height == b.height && a.distortion_model == b.distortion_model && a.D == b.D &&
         a.K == b.K;
}

} // namespace yawdepth
