#pragma once
/*!
  \file cloud_report.h
  \brief What a measured point cloud looks like (`measure --features klt --report DIR`): the points
  coloured by depth over the last image, and seen from above in that camera's frame with each
  depth's 2-sigma interval.

  Frames: the points are given in the world of the motion log (w_P); `cMw` is the world's pose in
  the camera of the image drawn on (the last frame), so that \f$ {}^cP = {}^cM_w\,{}^wP \f$.
  The colour of a point is its depth in that camera, on OpenCV's TURBO colour map from the nearest
  (blue) to the farthest (red) point drawn; both pictures carry the scale.
*/
#include <Eigen/Core>
#include <string>
#include <vector>
#include <opencv2/core.hpp>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/camera/camera_model.h>

namespace yawdepth {

/*! \brief One measured point of a cloud. */
struct CloudPoint {
  long id = 0;                                   //!< feature id
  Eigen::Vector3d w_P = Eigen::Vector3d::Zero(); //!< in the world frame (m)
  double sigma_z = 0;                            //!< 1-sigma depth uncertainty at its own frame (m)
};

/*! \brief What the cloud report draws. */
struct CloudReportInput {
  cv::Mat image;                 //!< the last frame's image (8-bit gray or BGR; the camera's size)
  CameraModel camera;            //!< the camera (with its image size)
  vpHomogeneousMatrix cMw;       //!< the world's pose in that frame's camera
  std::vector<CloudPoint> points; //!< the ok points
  std::string title;             //!< one line on both pictures
  std::string summary;           //!< report.txt's body (counts by status, what the estimator said)
};

/*!
  \brief The points in front of the camera and inside the image, drawn on the image as discs coloured
  by depth, with the colour scale (BGR, the image's size plus a 40 px scale strip below).
  Throws yawdepth::Error for an empty image or one of another size than the camera's.
*/
cv::Mat cloudOverlay(const CloudReportInput &in);
/*!
  \brief The points seen from above in the camera's frame (x right, depth up): each point a disc
  coloured by depth with its 2-sigma depth interval drawn along its ray, the camera and its field of
  view at the bottom, metric axes. A 900 x 700 BGR picture.
*/
cv::Mat cloudTopView(const CloudReportInput &in);
/*!
  \brief Write `report.txt` (title and summary), `overlay.png` and `top_view.png` into `dir`
  (created): all three or none.
*/
void writeCloudReport(const std::string &dir, const CloudReportInput &in);
/*! \brief The files writeCloudReport() writes into `dir` (for checks before writing). */
std::vector<std::string> cloudReportFiles(const std::string &dir);

} // namespace yawdepth
