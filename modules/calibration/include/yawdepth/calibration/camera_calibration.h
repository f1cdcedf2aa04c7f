#pragma once
/*!
  \file camera_calibration.h
  \brief Camera calibration from images of a chessboard or an AprilTag grid: intrinsics and Brown
  distortion (OpenCV's cv::calibrateCamera) or Kannala-Brandt fisheye distortion
  (cv::fisheye::calibrate), ViSP's two models (without distortion, and kud/kdu,
  each fitted by vpCalibration as ViSP's own calibration tool does), per-view errors, outlier
  views, parameter standard deviations, degeneracy checks and a coverage picture.
*/
#include <cstddef>
#include <functional>
#include <string>
#include <vector>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <visp3/core/vpCameraParameters.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/pattern.h>

namespace yawdepth {

/*! \brief The features detected in one calibration image. */
struct CalibrationView {
  std::string name;                       //!< image name (for messages)
  std::vector<FeatureObservation> features;  //!< observed (distorted) pixels with board feature ids
};

/*! \brief Detection over a set of calibration images. */
struct CalibrationDetections {
  int width = 0;                          //!< image width (px); all images must share the size
  int height = 0;                         //!< image height (px)
  std::vector<CalibrationView> views;     //!< the images where the pattern was found
  std::vector<std::string> failures;      //!< "NAME: reason" for every image where it was not
  std::vector<std::string> warnings;      //!< "NAME: warning" (FrameDetection::warnings, features not on the board)
  std::vector<FrameDetection> detections; //!< every image's detection, in input order (frame = index)
};

/*!
  \brief Detect the board in each image. Only the board's features are kept (AprilTag: the tag
  corners of tags that belong to `board`, not the centres).
  \throws yawdepth::Error when `images` is empty, the sizes differ, or the pattern is found in no
  image (the message says why, and hints at a wrong COLSxROWS when the board is found with one
  corner fewer or more per side). `progress`, when given, is called before each image with (images
  done, images in all), on the calling thread (the library never prints: a command line shows it).
*/
CalibrationDetections detectCalibrationViews(const BoardLayout &board, const std::vector<std::string> &names,
                                             const std::vector<cv::Mat> &images,
                                             const DetectorOptions &options = DetectorOptions(),
                                             const std::function<void(std::size_t, std::size_t)> &progress = {});

/*! \brief Options of calibrateCamera(). */
struct CameraCalibrationOptions {
  bool fix_aspect_ratio = false;    //!< fx = fy (cv::CALIB_FIX_ASPECT_RATIO, vpCalibration aspect ratio 1)
  bool fix_principal_point = false; //!< principal point at the image centre (OpenCV model only)
  /*! \brief The distortion model: Brown (OpenCV's coefficients) or Kannala-Brandt (cv::fisheye). */
  enum class Distortion {
    Auto,   //!< fit K4, K5 and K8 (and Fisheye when `try_fisheye`); keep the one with the least error on views left out (see below)
    K4,     //!< k1 k2 p1 p2
    K5,     //!< k1 k2 p1 p2 k3
    K8,     //!< k1 k2 p1 p2 k3 k4 k5 k6 (OpenCV's rational model)
    Fisheye //!< Kannala-Brandt k1 k2 k3 k4 (cv::fisheye::calibrate, no skew); not with fix_aspect_ratio
  };
  /*!
    Auto: each model is fitted with whole views left out (at most `cv_folds` folds, view k in fold
    k mod folds); a left-out view's pose is fitted to its own corners with the model's intrinsics
    and its reprojection error counted. Views left out only test where views were; where none
    reached, a flexible model can be far off: its projection uncertainty (projectionUncertainty(),
    RMS over the image) says how far. The score is sqrt(held-out RMS^2 + uncertainty^2); the model
    with the least score is chosen, or a simpler one within `simpler_within` of it, among the models whose fit is
    a usable camera over the whole image (checkCameraPlausible(): invertible, monotonic out to the
    image's corners). With fewer than 4 views: K4. A given model whose fit is not usable is an
    error, as is Auto when none is.
  */
  Distortion distortion = Distortion::Auto;
  /*! Auto: also fit and score the Kannala-Brandt fisheye model (last in the order of simplicity: it
      is chosen only when its score is better than every Brown model's by more than `simpler_within`);
      false: Auto never tries it. With fix_aspect_ratio it is scored as not usable. */
  bool try_fisheye = false;
  int cv_folds = 5;                 //!< Auto: at most this many folds of left-out views
  double simpler_within = 0.01;     //!< Auto: relative margin by which a simpler model is preferred
  bool estimate_k3 = false;         //!< with distortion Auto: the same as K5 (kept for older callers)
  bool zero_tangential = false;     //!< p1 = p2 = 0
  bool drop_outliers = false;       //!< recalibrate without the views flagged as outliers
  double outlier_ratio = 3.0;       //!< a view is an outlier when its RMS > ratio x median ...
  double outlier_min_px = 0.5;      //!< ... and > this (px)
  int min_views = 3;                //!< fewer views: error
  int min_points_per_view = 6;      //!< views with fewer points are not used
  double min_orientation_spread = 4.0 * M_PI / 180.0; //!< largest angle between board normals below this: degenerate
  bool fit_visp = true;             //!< also fit ViSP's two models with vpCalibration
};

/*! \brief Result for one view. */
struct CalibrationViewResult {
  std::string name;           //!< image name, as in CalibrationView
  int points = 0;             //!< number of the view's features
  double rms_px = 0;          //!< RMS reprojection error of the view's points (px), Brown model
  bool outlier = false;       //!< flagged as an outlier view
  bool used = true;           //!< used in the final calibration
  double tilt = 0;            //!< angle between the board normal and the optical axis (rad)
  Eigen::Isometry3d cMb = Eigen::Isometry3d::Identity(); //!< board pose in the camera frame
};

/*! \brief One distortion model as fitted and cross-validated by calibrateCamera(). */
struct DistortionModelScore {
  std::string name;          //!< "k1 k2 p1 p2", "k1 k2 p1 p2 k3", "k1..k6 p1 p2 (rational)" or "Kannala-Brandt k1..k4 (fisheye)"
  int coefficients = 0;      //!< 4, 5 or 8 (the fisheye model: 4)
  bool fisheye = false;      //!< the Kannala-Brandt model
  double rms_px = 0;         //!< RMS reprojection error over every view (px per point, as OpenCV's)
  double heldout_rms_px = 0; //!< RMS error on views left out (px per point); 0 when not computed
  /*! RMS over an 8 x 6 grid of the whole image of projectionUncertainty() (px): what the views
      leave unknown where they did not reach; 0 when not computed */
  double image_uncertainty_px = 0;
  /*! The criterion: sqrt(heldout_rms_px^2 + image_uncertainty_px^2), the expected error of a
      prediction anywhere in the image; 0 when not computed */
  double score_px = 0;
  bool chosen = false;       //!< the model of the result
  /*! Empty, or why the model cannot be used: its fit does not invert over the whole image
      (checkCameraPlausible()), typically a high-order model beyond the corners' reach. */
  std::string inadmissible;
};

/*! \brief Result of calibrateCamera(). */
struct CameraCalibration {
  CameraModel camera;              //!< Brown or (Distortion::Fisheye) Kannala-Brandt model with the image size
  double rms_px = 0;               //!< RMS reprojection error over the views used (px)
  /*! standard deviations of fx, fy, u0, v0, k1, k2, p1, p2, k3, k4, k5, k6 (0 for fixed parameters),
      the square roots of intrinsics_covariance's diagonal; for a Kannala-Brandt camera of fx, fy,
      u0, v0, k1, k2, k3, k4 in the first eight places (the last four 0) */
  std::vector<double> std_devs;
  std::vector<CalibrationViewResult> views; //!< every input view, in input order
  int views_used = 0;              //!< number of views in the final calibration
  double orientation_spread = 0;   //!< largest angle between two board normals (rad)
  double coverage = 0;             //!< fraction of a 8 x 6 image grid's cells with at least one point
  bool visp_fitted = false;        //!< the ViSP models below were fitted
  vpCameraParameters visp_without; //!< ViSP model without distortion (px, py, u0, v0)
  vpCameraParameters visp_with;    //!< ViSP model with distortion (px, py, u0, v0, kud, kdu)
  double visp_rms_without = 0;     //!< RMS reprojection error of the model without distortion (px)
  double visp_rms_with = 0;        //!< RMS reprojection error of the kud projection (px)
  double visp_rms_kdu = 0;         //!< RMS error of the kdu model (observed pixel undistorted, px)
  std::vector<std::string> notes;  //!< warnings for the user (few views, poor coverage, ...)
  std::vector<DistortionModelScore> models; //!< the models compared (one when the model was given)
  std::string model_reason;        //!< why the model was chosen, one line
  /*!
    Covariance of fx fy u0 v0 k1 k2 p1 p2 k3 k4 k5 k6 (a Kannala-Brandt camera: fx fy u0 v0 k1 k2 k3
    k4, then zeros) (12 x 12; rows and columns of fixed parameters are zero): the Gauss-Newton covariance of the final fit, poses marginalised (Schur complement),
    scaled by the residual variance SSE / (2N - parameters). Its diagonal is std_devs^2. (OpenCV's
    own deviations are larger by sqrt((2N - p) / (N - p)): it divides by N points, not 2N residuals.)
  */
  Eigen::Matrix<double, 12, 12> intrinsics_covariance = Eigen::Matrix<double, 12, 12>::Zero();
  /*! Projection uncertainty (px, 1 sigma along the worst direction, projectionUncertainty()) at the
      centres of an 8 x 6 grid of image cells, row-major. */
  std::vector<double> uncertainty_grid;
};

/*!
  \brief How uncertain the calibrated projection of pixel (u, v)'s ray is (px, 1 sigma along the
  worst direction), from `intrinsics_covariance` to first order. A change of the intrinsics that a
  small rotation of the camera undoes (the principal point against the camera's orientation) moves
  no measurement, since every pose absorbs it: that rotation, fitted over a 16 x 12 grid of the
  image, is removed first (mrcal's compensation of the camera frame, for points far away). What
  remains grows where the corners did not reach, at the image's edges and corners. For a
  Kannala-Brandt camera the covariance is of its k1..k4 (cv::fisheye's projection).
*/
double projectionUncertainty(const CameraCalibration &calibration, double u, double v);

/*!
  \brief Calibrate from detected views of `board`.
  \throws yawdepth::Error: too few views ("too few views: ..."), degenerate views ("degenerate
  views: ..."), a failed or non-finite solution.
*/
CameraCalibration calibrateCamera(const BoardLayout &board, const std::vector<CalibrationView> &views, int width,
                                  int height, const CameraCalibrationOptions &options = CameraCalibrationOptions());

/*!
  \brief The ViSP camera XML (vpXmlParserCamera::save) with both models under `camera_name` (empty:
  "Camera") and the image size. Throws yawdepth::Error when the ViSP models were not fitted or on
  failure.
  \param calibration The result. \param camera_name The camera's name. \param additional_info XML
  added to the camera's entry.
*/
std::string vispCameraXmlText(const CameraCalibration &calibration, const std::string &camera_name = "",
                              const std::string &additional_info = "");
/*! \brief vispCameraXmlText() written to `path` atomically (a temporary file beside it, renamed over it). */
void saveVispCameraXml(const std::string &path, const CameraCalibration &calibration,
                       const std::string &camera_name = "Camera", const std::string &additional_info = "");

/*!
  \brief The coverage picture: every point of every view on a blank image of the camera's size
  (a colour per view, outlier views as red crosses), an 8 x 6 grid whose empty cells are shaded.
*/
cv::Mat coverageImage(const CameraCalibration &calibration, const std::vector<CalibrationView> &views);
/*!
  \brief coverageImage() encoded as a file's bytes. \param calibration The result. \param views Its views.
  \param extension The format, as for cv::imencode (".png").
*/
std::string coverageImageBytes(const CameraCalibration &calibration, const std::vector<CalibrationView> &views,
                               const std::string &extension);
/*! \brief coverageImage() written as a PNG (or the format of the path's extension), atomically; throws yawdepth::Error on failure. */
void writeCoverageImage(const std::string &path, const CameraCalibration &calibration,
                        const std::vector<CalibrationView> &views);

} // namespace yawdepth
