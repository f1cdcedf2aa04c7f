#include "servo_sim.h"

#include <cmath>
#include <limits>
#include <yawdepth/error.h>

namespace servo_sim {

using yawdepth::Error;
using yawdepth::rotY;

yawdepth::MotionSample UnicyclePanRobot::sample(long frame) const
{
  yawdepth::MotionSample s;
  s.frame = frame;
  const Eigen::Vector3d p = Eigen::Vector3d(x, 0, z) + rotY(heading) * Eigen::Vector3d(0, 0, axle_to_yaw);
  s.x = p.x();
  s.y = p.y();
  s.z = p.z();
  s.heading = heading;
  s.yaw = pan;
  return s;
}

vpHomogeneousMatrix UnicyclePanRobot::wMc() const { return yawdepth::wMc(rig, sample()); }

vpMatrix UnicyclePanRobot::cJq() const
{
  // Camera origin in the robot frame (wheel axle centre, camera convention), and e_y x p = (p_z, 0, -p_x).
  const Eigen::Matrix3d Rq = rotY(pan);
  const Eigen::Vector3d r_off = Rq * rig.cameraOffset();
  const Eigen::Vector3d r_c = Eigen::Vector3d(0, 0, axle_to_yaw) + r_off;
  auto cross_y = [](const Eigen::Vector3d &p) { return Eigen::Vector3d(p.z(), 0, -p.x()); };
  const Eigen::Vector3d lin_v = Rq.transpose() * Eigen::Vector3d(0, 0, 1);
  const Eigen::Vector3d lin_w = Rq.transpose() * cross_y(r_c);
  const Eigen::Vector3d lin_q = Rq.transpose() * cross_y(r_off);
  vpMatrix J(6, 3, 0.0);
  for (unsigned i = 0; i < 3; ++i) {
    J[i][0] = lin_v(i);
    J[i][1] = lin_w(i);
    J[i][2] = lin_q(i);
  }
  J[4][1] = 1.0;
  J[4][2] = 1.0;
  return J;
}

Eigen::Vector3d UnicyclePanRobot::visionVelocity(double v, double omega) const
{
  return Eigen::Vector3d(omega * axle_to_yaw, 0, v);
}

void UnicyclePanRobot::step(const vpColVector &qdot, double dt)
{
  if (qdot.size() != 3)
    throw Error("robot: expected 3 joint rates (v, omega, pan rate)");
  const double v = qdot[0], w = qdot[1];
  const double h0 = heading, h1 = heading + w * dt;
  if (std::abs(w * dt) > 1e-12) {
    x += v / w * (std::cos(h0) - std::cos(h1));
    z += v / w * (std::sin(h1) - std::sin(h0));
  } else {
    x += v * dt * std::sin(h0);
    z += v * dt * std::cos(h0);
  }
  heading = h1;
  pan += qdot[2] * dt;
}

void UnicyclePanRobot::placeCamera(const vpHomogeneousMatrix &wMc_target, double heading_rad)
{
  const double psi = std::atan2(wMc_target[0][2], wMc_target[0][0]);
  heading = heading_rad;
  pan = psi - heading_rad;
  const Eigen::Vector3d c(wMc_target[0][3], wMc_target[1][3], wMc_target[2][3]);
  const Eigen::Vector3d p = c - rotY(heading) * (Eigen::Vector3d(0, 0, axle_to_yaw) + rotY(pan) * rig.cameraOffset());
  x = p.x();
  z = p.z();
}

const char *toString(ServoDepthMode m)
{
  switch (m) {
  case ServoDepthMode::True:
    return "true";
  case ServoDepthMode::Constant:
    return "constant";
  case ServoDepthMode::Estimated:
    return "estimated";
  }
  return "?";
}

ServoDepthMode servoDepthModeFromString(const std::string &s)
{
  if (s == "true")
    return ServoDepthMode::True;
  if (s == "constant")
    return ServoDepthMode::Constant;
  if (s == "estimated")
    return ServoDepthMode::Estimated;
  throw Error("unknown depth mode '" + s + "' (expected true, constant or estimated)");
}

yawdepth::CameraModel ServoSimOptions::defaultCamera()
{
  return yawdepth::CameraModel::brown(600, 600, 320, 240, {-0.05, 0, 0, 0}, 640, 480);
}

void ServoSimOptions::validate() const
{
  if (!(dt > 0) || !(lambda > 0) || max_iterations < 1 || !(tolerance_px > 0) || !(tag_size > 0) ||
      !(desired_depth > 0) || !(sigma_px >= 0) || !(sigma_odom_rel >= 0) || !(sigma_pan >= 0) || !(max_v > 0) ||
      !(max_omega > 0) || !(max_pan_rate > 0))
    throw Error("servo simulation: invalid options");
  if (depth == ServoDepthMode::Constant && !(constant_error > -1.0))
    throw Error("servo simulation: constant_error must be above -1 (the depth must stay positive)");
  if (camera.width() == 0 || camera.height() == 0)
    throw Error("servo simulation: the camera needs an image size");
}

namespace {

// Point the camera (heading and axle fixed) at `target` plus `offset` rad of yaw. The optical centre
// moves with the pan (it is off the pan axis), so the pan is found by a fixed-point iteration.
void aimPan(UnicyclePanRobot &robot, const Eigen::Vector3d &target, double offset)
{
  for (int it = 0; it < 20; ++it) {
    const vpHomogeneousMatrix M = robot.wMc();
    const Eigen::Vector3d d = target - Eigen::Vector3d(M[0][3], M[1][3], M[2][3]);
    robot.pan = std::atan2(d.x(), d.z()) + offset - robot.heading;
  }
}

} // namespace

TagScene::TagScene(const ServoSimOptions &o) : camera(o.camera), sigma_px(o.sigma_px)
{
  o.validate();
  const double h = o.tag_size / 2;
  ids = {1, 2, 3, 4};
  w_P = {{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
  wMcd[2][3] = -o.desired_depth;
  start.axle_to_yaw = o.axle_to_yaw;
  start.rig = o.rig;
  const double heading_d = o.side_view ? -M_PI / 2 : 0.0;
  start.placeCamera(wMcd, heading_d);
  // Back along the robot's path, off to one side, turned, the pan aimed near the tag.
  const Eigen::Vector3d fwd(std::sin(heading_d), 0, std::cos(heading_d)), right(std::cos(heading_d), 0, -std::sin(heading_d));
  const double back = o.side_view ? 0.5 : 0.8, lateral = o.side_view ? -0.12 : 0.15, turn = o.side_view ? 0.1 : 0.15;
  const Eigen::Vector3d p = Eigen::Vector3d(start.x, 0, start.z) - back * fwd + lateral * right;
  start.x = p.x();
  start.z = p.z();
  start.heading = heading_d + turn;
  aimPan(start, Eigen::Vector3d::Zero(), 0.05);
}

Eigen::Vector3d TagScene::cameraPoint(const vpHomogeneousMatrix &cMw, std::size_t i) const
{
  const vpColVector P = cMw * vpColVector{w_P[i].x(), w_P[i].y(), w_P[i].z(), 1.0};
  return Eigen::Vector3d(P[0], P[1], P[2]);
}

CornerView TagScene::observe(const UnicyclePanRobot &robot, Noise &noise) const
{
  CornerView view;
  const vpHomogeneousMatrix cMw = robot.wMc().inverse();
  for (std::size_t i = 0; i < w_P.size(); ++i) {
    const Eigen::Vector3d P = cameraPoint(cMw, i);
    if (!(P.z() > 1e-3)) {
      view.lost = true;
      view.pixels.emplace_back(Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN()));
      continue;
    }
    const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(P.x() / P.z(), P.y() / P.z()));
    if (!(uv.x() >= 0 && uv.x() <= camera.width() - 1 && uv.y() >= 0 && uv.y() <= camera.height() - 1))
      view.lost = true;
    view.pixels.push_back(uv);
    const double du = sigma_px * noise(); // u first, then v: the draws' order is part of the seeded run
    const double dv = sigma_px * noise();
    view.observed.emplace_back(ids[i], vpImagePoint(uv.y() + dv, uv.x() + du));
    view.true_Z.push_back(P.z());
  }
  return view;
}

} // namespace servo_sim
