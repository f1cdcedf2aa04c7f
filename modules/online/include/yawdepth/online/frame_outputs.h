#pragma once
/*!
  \file frame_outputs.h
  \brief What a measured image gives to look at: its point cloud (camera and world frames, depth
  sigma, the 2-sigma interval along each ray, the gray level), its points counted by status, and the
  image with its tracks drawn. The ROS node publishes these as they are (PointCloud2,
  MarkerArray, diagnostics, Image); any other front end can too.

  Frames: c is the camera at the image's time (yawdepth's camera: z forward, x right, y down, as a ROS
  optical frame), w the world of the pose stream (the motion log's), \f$ {}^wT_c \f$ = wMc(rig,
  frame.pose).
*/
#include <cstddef>
#include <utility>
#include <vector>
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/online/online_measurer.h>

namespace yawdepth {

/*! \brief One point of a measured image's cloud. */
struct CloudPoint {
  long id = 0;              //!< Feature id.
  double u = 0, v = 0;      //!< Observed pixel (px).
  Eigen::Vector3d c_P;      //!< The point in the camera frame at the image (m).
  Eigen::Vector3d w_P;      //!< The point in the world (m).
  double sigma_z = 0;       //!< 1-sigma of its depth, camera Z (m).
  float intensity = 0;      //!< The image's gray level at the pixel (0..255).
  Eigen::Vector3d w_near;   //!< The near end of the depth interval Z - k sigma_z along the ray, world (m).
  Eigen::Vector3d w_far;    //!< The far end, Z + k sigma_z, world (m).
};

/*!
  \brief The `ok` points of `frame` (the others have no position), in the order of frame.points.
  \param frame A frame from OnlineMeasurer::process() (its image is used for the intensities).
  \param rig The measurer's rig (for the camera's pose in the world).
  \param interval_sigmas k of the depth interval [Z - k sigma, Z + k sigma] (>= 0; the near end is
         clamped in front of the camera). Throws yawdepth::Error for a negative or non-finite k.
*/
std::vector<CloudPoint> frameCloud(const OnlineFrame &frame, const YawRig &rig, double interval_sigmas = 2.0);

/*! \brief How many of `frame`'s points have each status, in the order of the Status enum, only the
    statuses present. */
std::vector<std::pair<Status, std::size_t>> countByStatus(const OnlineFrame &frame);

/*!
  \brief `frame`'s image (BGR) with its tracks drawn: each point a circle, green for `ok`, yellow for
  `too_few_frames` (not yet enough frames) and red for every other status; an `ok` point's depth
  (m, 2 decimals) beside it when `label_depths`.
*/
cv::Mat drawTracks(const OnlineFrame &frame, bool label_depths = true);

} // namespace yawdepth
