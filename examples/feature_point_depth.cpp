/*
  feature_point_depth: give ViSP's visual servoing the depth yawdepth estimates.

  vpFeaturePoint needs each point's depth Z to build its interaction matrix. Instead of a constant
  guess, use the depth estimated from the robot's motion, but only when the estimate's status is
  ok; otherwise (too little parallax, a feature seen once, ...) fall back to a prior depth.

  The scene: camera at yaw 0 ("front view"), robot driving 20 mm forward, three features:
  one off-axis (gets a depth), one on the optical axis (the focus of expansion: no parallax, so
  "degenerate") and one seen for the first time (too_few_frames).
*/
#include <cmath>
#include <cstdio>
#include <vector>

#include <Eigen/Core>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/core/vpMatrix.h>
#include <visp3/visual_features/vpFeaturePoint.h>

#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/geometry/rig.h>

namespace {

// Observed pixel of a point given in the camera frame of the first row (synthetic tracker).
yawdepth::Observation observe(const yawdepth::CameraModel &camera, const yawdepth::YawRig &rig,
                              const std::vector<yawdepth::MotionSample> &motion, std::size_t row,
                              const vpColVector &c0_P)
{
  const vpColVector c_P = yawdepth::wMc(rig, motion[row]).inverse() * (yawdepth::wMc(rig, motion[0]) * c0_P);
  const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(c_P[0] / c_P[2], c_P[1] / c_P[2]));
  return yawdepth::Observation{motion[row].frame, uv.x(), uv.y()};
}

} // namespace

int main()
{
  const yawdepth::CameraModel camera =
      yawdepth::CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
  const yawdepth::YawRig rig(Eigen::Vector3d(-0.1503, 0.0, 0.0));

  // Motion log: frames 10 and 11, 20 mm forward, camera yaw 0.
  std::vector<yawdepth::MotionSample> motion(2);
  motion[0].frame = 10;
  motion[1].frame = 11;
  motion[1].z = 0.020;

  // Feature tracks, as a tracker would deliver them (observed, distorted pixels).
  std::vector<yawdepth::Track> tracks(3);
  const vpColVector off_axis{0.10, -0.05, 0.80, 1.0}, on_axis{0.0, 0.0, 1.0, 1.0}, fresh{-0.08, 0.04, 0.9, 1.0};
  tracks[0] = {0, {observe(camera, rig, motion, 0, off_axis), observe(camera, rig, motion, 1, off_axis)}};
  tracks[1] = {1, {observe(camera, rig, motion, 0, on_axis), observe(camera, rig, motion, 1, on_axis)}};
  tracks[2] = {2, {observe(camera, rig, motion, 1, fresh)}};

  const double prior_Z = 1.0; // what the servo would use without an estimate (m)
  std::vector<vpFeaturePoint> features(tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    // Depth at the track's last frame (here the current frame 11), by the exact two-view method.
    const yawdepth::PointEstimate e = yawdepth::estimateTrack(camera, rig, motion, tracks[i]);
    const double Z = e.ok() ? e.c_P.z() : prior_Z; // use the estimate only when valid

    // The feature's current normalised coordinates, undistorted with the same camera model
    // (vpImagePoint is (row i = v, column j = u)).
    const yawdepth::Observation &ob = tracks[i].observations.back();
    double x = 0, y = 0;
    camera.pixelToMeter(vpImagePoint(ob.v, ob.u), x, y);
    features[i].buildFrom(x, y, Z);

    std::printf("feature %ld: status %-14s Z = %.4f m (%s)  x = %+.4f y = %+.4f\n", tracks[i].id,
                yawdepth::toString(e.status), features[i].get_Z(), e.ok() ? "estimated" : "prior", x, y);
  }

  // In a servo loop the features already exist: refresh only the depth with set_Z(), again only for
  // a valid estimate. The interaction matrix then uses it: its first row starts with -1/Z.
  const yawdepth::PointEstimate e0 = yawdepth::estimateTrack(camera, rig, motion, tracks[0]);
  if (e0.ok())
    features[0].set_Z(e0.c_P.z());
  const vpMatrix L = features[0].interaction();
  std::printf("feature 0 interaction matrix, first row: %.4f %.4f %.4f %.4f %.4f %.4f (-1/Z = %.4f)\n", L[0][0],
              L[0][1], L[0][2], L[0][3], L[0][4], L[0][5], -1.0 / features[0].get_Z());
  return 0;
}
