/*
  depth_from_two_frames: the smallest use of yawdepth.

  A robot carries a camera on a yaw mechanism. Between two frames it drives 20 mm forward with the
  camera turned to the side (yaw = pi/2, the paper's "side view"). From one feature's pixel in each
  frame and the motion log, estimateExact() gives the feature's 3D point at the second frame.

  The feature's pixels are synthesised here from a known 3D point, so the printed estimate can be
  compared with the truth; in an application they come from a tracker.
*/
#include <cmath>
#include <cstdio>

#include <Eigen/Core>
#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpTranslationVector.h>

#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/two_view.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

int main()
{
  // 1. The camera: ViSP pinhole parameters (px, py, u0, v0) of the paper's 640x480 camera.
  //    CameraModel wraps them; with distortion, use CameraModel::brown(...) or a ViSP
  //    perspectiveProjWithDistortion model instead.
  vpCameraParameters cam(1734.1, 1734.5, 319.2, 241.4);
  const yawdepth::CameraModel camera(cam, 640, 480);

  // 2. The rig: where the optical centre sits relative to the yaw axis at yaw 0 (metres, in the
  //    vision frame). The paper's camera is Lb = 150.3 mm to the left of the axis.
  const yawdepth::YawRig rig(vpTranslationVector(-0.1503, 0.0, 0.0));

  // 3. Two rows of the motion log: vision-frame position in the world (m), robot heading and
  //    camera yaw (rad). The robot moves 20 mm along its forward axis (+Z); the camera looks to
  //    the side.
  yawdepth::MotionSample prev, cur;
  prev.frame = 0;
  prev.yaw = M_PI / 2;
  cur.frame = 1;
  cur.z = 0.020;
  cur.yaw = M_PI / 2;

  // 4. A known 3D point, 0.6 m in front of the camera at the first frame (camera frame, metres).
  //    Move it to the world, then into the second camera frame, and project both into pixels.
  const vpColVector c_P_prev{0.05, 0.02, 0.60, 1.0};
  const vpColVector w_P = yawdepth::wMc(rig, prev) * c_P_prev;
  const vpColVector c_P_cur = yawdepth::wMc(rig, cur).inverse() * w_P;
  const Eigen::Vector2d uv_prev = camera.project(Eigen::Vector2d(c_P_prev[0] / c_P_prev[2], c_P_prev[1] / c_P_prev[2]));
  const Eigen::Vector2d uv_cur = camera.project(Eigen::Vector2d(c_P_cur[0] / c_P_cur[2], c_P_cur[1] / c_P_cur[2]));
  std::printf("feature pixels: (%.3f, %.3f) -> (%.3f, %.3f)\n", uv_prev.x(), uv_prev.y(), uv_cur.x(), uv_cur.y());

  // 5. Estimate. The result is the point at the *current* frame, with a status that says whether
  //    it is valid and a first-order covariance for the default noise model (0.3 px, 1 mm of
  //    odometry, 0.05 deg of heading and yaw; set TwoViewOptions::noise to your own).
  const yawdepth::PointEstimate exact = yawdepth::estimateExact(camera, rig, prev, cur, uv_prev, uv_cur);
  if (!exact.ok()) { // always check: degenerate geometry gives a status word, never a wrong number
    std::printf("no estimate: %s\n", yawdepth::toString(exact.status));
    return 0;
  }
  std::printf("exact: Zc = %.6f m (true %.6f), sigma_zc = %.2f mm, status = %s\n", exact.c_P.z(), c_P_cur[2],
              1e3 * exact.sigmaZ(), yawdepth::toString(exact.status));
  // The same point in the vision frame (on the robot, at the yaw axis), eq. (7). As ViSP types:
  // exact.cP(), exact.vP() (vpColVector) and exact.covariance() (vpMatrix).
  const vpColVector v_P = exact.vP();
  std::printf("vision frame: X = %.4f, Y = %.4f, Z = %.4f m\n", v_P[0], v_P[1], v_P[2]);

  // 6. The paper's eq. (5), for comparison. It is first order in the increment and returns the
  //    depth of the *previous* frame, so it is off by about dZc/Z, where dZc is the camera's motion
  //    along its own optical axis. At side view dZc = 0, and the bias vanishes...
  const yawdepth::PointEstimate paper = yawdepth::estimatePaper(camera, rig, prev, cur, uv_prev, uv_cur);
  std::printf("paper, yaw 90 deg: Zc = %.6f m, bias %+.3f mm\n", paper.c_P.z(), 1e3 * (paper.c_P.z() - c_P_cur[2]));

  // ...but with the camera at yaw 45 deg the camera moves 14 mm along its axis, and the bias shows.
  prev.yaw = cur.yaw = M_PI / 4;
  const vpColVector c_P45_cur = yawdepth::wMc(rig, cur).inverse() * (yawdepth::wMc(rig, prev) * c_P_prev);
  const Eigen::Vector2d uv45_prev = camera.project(Eigen::Vector2d(c_P_prev[0] / c_P_prev[2], c_P_prev[1] / c_P_prev[2]));
  const Eigen::Vector2d uv45_cur = camera.project(Eigen::Vector2d(c_P45_cur[0] / c_P45_cur[2], c_P45_cur[1] / c_P45_cur[2]));
  const yawdepth::PointEstimate paper45 = yawdepth::estimatePaper(camera, rig, prev, cur, uv45_prev, uv45_cur);
  const yawdepth::PointEstimate exact45 = yawdepth::estimateExact(camera, rig, prev, cur, uv45_prev, uv45_cur);
  std::printf("yaw 45 deg: true Zc = %.6f m, exact bias %+.3f mm, paper bias %+.3f mm\n", c_P45_cur[2],
              1e3 * (exact45.c_P.z() - c_P45_cur[2]), 1e3 * (paper45.c_P.z() - c_P45_cur[2]));
  return 0;
}
