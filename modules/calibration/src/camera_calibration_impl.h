#pragma once
/*
  Private to yawdepth::calibration: what the files of camera calibration share (not installed).
  camera_fit.cpp fits OpenCV's models on subsets of the views (CameraFit) and keeps the final fit;
  model_selection.cpp chooses the distortion model by the held-out error; visp_models.cpp fits ViSP's
  two models and writes ViSP's camera file; calibration_coverage.cpp measures the image's coverage
  and the projection uncertainty; camera_calibration.cpp drives them (detectCalibrationViews,
  calibrateCamera).
*/
#include <Eigen/Core>
#include <cstddef>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>
#include <yawdepth/calibration/camera_calibration.h>
#include <yawdepth/camera/camera_model.h>

namespace yawdepth {
namespace calibration_detail {

using Distortion = CameraCalibrationOptions::Distortion;

/* OpenCV's solution of a fit: K, the distortion coefficients, a board pose per view of the fit (in
   the fit's order) and cv::calibrateCamera's standard deviations of the intrinsics. */
struct OpenCvSolution {
  cv::Mat K, dist;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_intrinsics;
};

/* The board's correspondences in every view, and OpenCV's fits and their diagnostics on subsets of
   the views (`idx`: indices into `views`; a fit's poses follow idx's order). */
struct CameraFit {
  const std::map<long, Eigen::Vector3d> pts;
  const std::vector<CalibrationView> &views;
  const int width, height;
  const CameraCalibrationOptions &options;
  std::vector<std::vector<cv::Point3f>> object; // per view: board points with a finite observation
  std::vector<std::vector<cv::Point2f>> image;  // per view: their pixels

  OpenCvSolution solve(const std::vector<std::size_t> &idx, Distortion d) const;
  double heldOut(const std::vector<std::size_t> &idx, Distortion d, const OpenCvSolution &all) const;
  bool intrinsicsCovariance(const std::vector<std::size_t> &idx, const OpenCvSolution &s, Distortion d,
                            Eigen::Matrix<double, 12, 12> &out) const;
  std::string admissibility(const OpenCvSolution &s, Distortion d, const std::vector<std::size_t> &idx) const;
};

/* An OpenCV or ViSP message on one line (newlines and tabs as spaces, no trailing space). */
std::string oneLine(std::string s);

/* The name of a distortion model, as the reports print it. */
std::string modelName(Distortion d);

/* The projection of a view's board points through a fit's K and distortion (`d`: its model). */
std::vector<cv::Point2f> projectView(const std::vector<cv::Point3f> &obj, const cv::Mat &rvec, const cv::Mat &tvec,
                                     const cv::Mat &K, const cv::Mat &dist, Distortion d);

/* d(pixel)/d(fx fy u0 v0 k1..k6) (2N x 12) and d(pixel)/d(rvec tvec) (2N x 6) of OpenCV's projection
   (camera_fit.cpp); the projections into *proj when given. */
void projectionJacobians(const std::vector<cv::Point3f> &obj, const cv::Mat &rvec, const cv::Mat &tvec, const cv::Mat &K,
                         const cv::Mat &dist, bool fisheye, Eigen::MatrixXd &Jint, Eigen::MatrixXd &Jpose,
                         std::vector<cv::Point2d> *proj = nullptr);

/* Adds the squared pixel errors of projections against the observed points to sse (a float
   projection is differenced in float, as before). */
template <class Point>
void addSquaredErrors(const std::vector<Point> &proj, const std::vector<cv::Point2f> &observed, double &sse)
{
  for (std::size_t j = 0; j < proj.size(); ++j) {
    const double du = proj[j].x - observed[j].x, dv = proj[j].y - observed[j].y;
    sse += du * du + dv * dv;
  }
}

/* The camera of a fit: Brown (5 coefficients, 8 for the rational model) or Kannala-Brandt (4). */
CameraModel cameraOf(const OpenCvSolution &s, Distortion d, int width, int height);

/* Projection uncertainty at the centres of the 8 x 6 cells of the image, row by row
   (calibration_coverage.cpp). */
std::vector<double> uncertaintyGrid(const CameraCalibration &calibration, int width, int height);

/* Fills fit.object and fit.image and the views' names and point counts; the views with enough
   points (camera_fit.cpp). */
std::vector<std::size_t> collectCorrespondences(CameraFit &fit, CameraCalibration &result);

/* The distortion model: given, or chosen by the held-out error (model_selection.cpp). */
Distortion chooseModel(const CameraFit &fit, const std::vector<std::size_t> &usable, CameraCalibration &result);

/* The fit of `model` on the `used` views, refitted once without its outlier views when the options
   drop them (camera_fit.cpp). */
OpenCvSolution fitDroppingOutliers(const CameraFit &fit, Distortion model, int min_views, std::vector<std::size_t> &used,
                                   CameraCalibration &result);

/* The final fit's camera, its covariance, standard deviations and uncertainty grid (camera_fit.cpp). */
void storeCamera(const CameraFit &fit, const OpenCvSolution &sol, Distortion model, const std::vector<std::size_t> &used,
                 CameraCalibration &result);

/* Share of the 8 x 6 cells of the image with a corner of a used view (calibration_coverage.cpp). */
double coverageOf(const CameraFit &fit, const std::vector<std::size_t> &used);

/* ViSP's two models, or a note why not (visp_models.cpp). */
void fitVispModels(const CameraFit &fit, const OpenCvSolution &sol, const std::vector<std::size_t> &used,
                   CameraCalibration &result);

} // namespace calibration_detail
} // namespace yawdepth
