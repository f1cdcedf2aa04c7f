#include <yawdepth/servo/pioneer_pan.h>

#include <cmath>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {
// vpPioneerPan's geometry (vpPioneerPan::set_mMp() and set_cMe(), ViSP 3.5).
constexpr double kPanAhead = 0.103;  // pan axis ahead of the wheels' axis (m)
constexpr double kPanHeight = 0.27;  // pan frame above the floor (m)
constexpr double kCameraAbove = 0.065; // optical centre above the pan frame (m)
} // namespace

YawRig pioneerPanRig() { return YawRig(Eigen::Vector3d(0.0, -kCameraAbove, 0.0)); }

MotionSample pioneerPanOdometry(double x_m, double y_m, double theta, double q_pan, long frame)
{
  if (!std::isfinite(x_m) || !std::isfinite(y_m) || !std::isfinite(theta) || !std::isfinite(q_pan))
    throw Error("pioneer odometry: x, y, theta and the pan reading must be finite");
  MotionSample s;
  s.frame = frame;
  const double wx = x_m + kPanAhead * std::cos(theta), wy = y_m + kPanAhead * std::sin(theta);
  s.x = -wy;
  s.y = -kPanHeight;
  s.z = wx;
  s.heading = -theta;
  s.yaw = q_pan;
  return s;
}

vpHomogeneousMatrix pioneerPanWorld()
{
  vpHomogeneousMatrix oMw; // identity translation
  vpRotationMatrix oRw;
  oRw[0][0] = 0;
  oRw[0][1] = -1;
  oRw[0][2] = 0;
  oRw[1][0] = 0;
  oRw[1][1] = 0;
  oRw[1][2] = -1;
  oRw[2][0] = 1;
  oRw[2][1] = 0;
  oRw[2][2] = 0;
  oMw.insert(oRw);
  return oMw;
}

} // namespace yawdepth
