#pragma once
/*
  Private to yawdepth::calibration: a board's points by feature id, and one view's board pose by
  PnP on its undistorted features (shared by the yaw-rig and the hand-eye calibrations).
*/
#include <map>
#include <vector>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/pattern.h>

namespace yawdepth {
namespace calibration_detail {

/* The board's points by feature id: a chessboard's corners, an AprilTag grid's tag corners (not
   the tag centres, ids multiple of 5). */
std::map<long, Eigen::Vector3d> boardPoints(const BoardLayout &board);

/* One view's features with a known board point that can be undistorted: the board points P and
   the observed pixels uv; and the board's pose in the camera cMb by PnP (IPPE, then iterative) on
   them. False (cMb untouched) with fewer than `min_points` such features or when PnP fails. */
bool boardPoseByPnP(const CameraModel &camera, const std::map<long, Eigen::Vector3d> &points,
                    const std::vector<FeatureObservation> &features, int min_points, Eigen::Isometry3d &cMb,
                    std::vector<Eigen::Vector3d> &P, std::vector<Eigen::Vector2d> &uv);

/* The pose [R(rvec) | tvec] of an OpenCV rotation vector and translation (CV_64F). */
Eigen::Isometry3d isometryOf(const cv::Mat &rvec, const cv::Mat &tvec);

} // namespace calibration_detail
} // namespace yawdepth
