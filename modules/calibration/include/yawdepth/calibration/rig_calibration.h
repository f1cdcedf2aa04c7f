#pragma once
/*!
  \file rig_calibration.h
  \brief Calibration of the yaw rig from images of a static board taken at several yaw readings:
  the camera offset t0 (the paper's Lb, as a vector), the yaw axis direction and the zero of the
  yaw reading, with their uncertainties.

  Model (rig.h, generalised): the camera pose in the vision frame at true yaw theta is
  \f$ {}^vT_c(\theta) = [R_a(\theta) \;|\; R_a(\theta)\, t_0] \f$, with \f$ R_a \f$ the rotation
  about the unit axis `a` (ideally +Y) and \f$ \theta = \text{reading} + \text{yaw\_offset} \f$.
  The vision frame is the camera frame at true yaw 0. Each image's vision-frame pose comes from
  its motion-log row; the board is fixed in the world. Unknowns: the board pose (6), t0, the
  axis (2 dof), the yaw offset; found by Levenberg–Marquardt on the reprojection error of every
  feature through the calibrated camera, uncertainties from the Gauss–Newton information scaled
  by the residual variance.

  Gauge (what the images cannot tell):
  - the component of t0 along the yaw axis moves the camera and the board together: it is fixed
    at its initial value (`initial_offset.y()`, default 0). It does not enter any estimate.
  - the yaw offset turns the board about the axis just like the camera: it is observable only
    when the robot translates between images (its direction tells where the robot's forward is),
    or when the board stands square to the robot's forward direction (`board_square`: the board's
    normal in the vision frame has no component along X). Otherwise it is fixed at
    `initial_yaw_offset` and reported as not estimated.
*/
#include <string>
#include <vector>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <yawdepth/calibration/board_scale.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/pattern.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief One image of the rig calibration: its motion-log row (yaw = the reading) and features. */
struct RigView {
  MotionSample sample;                   //!< the image's motion-log row (yaw = the reading)
  std::vector<FeatureObservation> features; //!< the board's features detected in the image
};

/*! \brief Options of calibrateRig(). */
struct RigCalibrationOptions {
  Eigen::Vector3d initial_offset = Eigen::Vector3d::Zero(); //!< start for t0; its y stays fixed (gauge)
  bool use_initial_offset = false; //!< start from initial_offset instead of the closed-form estimate
  double initial_yaw_offset = 0;   //!< start (or fixed value) for the yaw offset (rad)
  bool board_square = false;       //!< the board faces the robot squarely: fixes the yaw zero
  bool estimate_axis = true;       //!< estimate the axis direction (else +Y)
  double min_yaw_span = 20.0 * M_PI / 180.0; //!< readings must span this much ...
  int min_distinct_yaws = 3;       //!< ... with at least this many distinct values (0.2 deg apart)
  double min_baseline = 0.02;      //!< robot translation (m) from which the yaw offset is estimated
  int min_points_per_view = 4;     //!< views with fewer points are not used
  /*! A fit whose reprojection RMS is larger failed (wrong yaw sign or unit, shuffled readings, a
      wrong camera): calibrateRig() refuses it rather than return a rig that looks valid. */
  double max_rms_px = 3.0;
  double max_offset = 2.0;         //!< a camera offset longer than this (m) is refused the same way
  double max_offset_sigma = 0.05;  //!< ... and one this uncertain (m, 1-sigma of x or z)
  /*! Check the board's size against the robot's translation (board_scale.h) when it moved (the
      yaw zero from RobotMotion): the fit again with a scale of the board's points free. A static
      robot cannot tell the size: a wrong one scales the camera offset by the same factor, unseen. */
  bool check_board_scale = true;
  BoardScaleOptions board_scale; //!< when the scale differs enough from 1 to say so
};

/*! \brief How the yaw offset was obtained. */
enum class YawZeroSource {
  Fixed,       //!< not observable: kept at the initial value
  RobotMotion, //!< from the robot's translation between images
  BoardSquare  //!< from the board standing square to the robot
};

/*! \brief Result of calibrateRig(). 1-sigma uncertainties; 0 for fixed quantities. */
struct RigCalibration {
  Eigen::Vector3d camera_offset = Eigen::Vector3d::Zero();       //!< t0: the optical centre in the vision frame at yaw 0 (m)
  Eigen::Vector3d camera_offset_sigma = Eigen::Vector3d::Zero(); //!< 1-sigma of camera_offset (m)
  Eigen::Vector3d yaw_axis = Eigen::Vector3d::UnitY();           //!< unit yaw axis in the vision frame
  Eigen::Vector3d yaw_axis_sigma = Eigen::Vector3d::Zero();      //!< 1-sigma of yaw_axis
  double yaw_offset = 0;       //!< yaw offset: true yaw = reading + yaw_offset (rad)
  double yaw_offset_sigma = 0; //!< 1-sigma of yaw_offset (rad)
  YawZeroSource yaw_zero = YawZeroSource::Fixed; //!< how yaw_offset was obtained
  Eigen::Isometry3d v0Mb = Eigen::Isometry3d::Identity(); //!< board pose in the first view's vision frame
  double rms_px = 0;               //!< RMS reprojection error (px, per coordinate pair)
  std::vector<double> view_rms_px; //!< per view
  int views = 0;                   //!< number of views used
  int points = 0;                  //!< number of features used, over every view
  int iterations = 0;              //!< Levenberg–Marquardt iterations
  double yaw_span = 0;             //!< span of the yaw readings (rad)
  int distinct_yaws = 0;           //!< number of distinct yaw readings (0.2 deg apart)
  double baseline = 0;             //!< largest robot translation between views (m)
  /*! The board's size as the robot's translation sees it; NotEstimated for a static robot (the
      images cannot tell it, and a wrong size scales camera_offset by the same factor). */
  BoardScaleCheck board_scale;
};

/*!
  \brief Estimate the rig from views of a static board (see the file's description).
  \throws yawdepth::Error: too few views, yaw span too small ("yaw readings span only ..."), a
  failed solve.
*/
RigCalibration calibrateRig(const CameraModel &camera, const BoardLayout &board, const std::vector<RigView> &views,
                            const RigCalibrationOptions &options = RigCalibrationOptions());

/*!
  \brief The rig file text (YAML): `camera_offset`, `yaw_offset`, `yaw_axis` (what readRigFile()
  reads) and, as extra keys, `camera_offset_sigma`, `yaw_offset_sigma`, `yaw_axis_sigma`,
  `yaw_offset_estimated` (bool), `reprojection_rms_px`.
*/
std::string rigCalibrationYaml(const RigCalibration &rig);

} // namespace yawdepth
