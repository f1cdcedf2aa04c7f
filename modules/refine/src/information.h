#pragma once
/*
  Private to yawdepth::refine: the Gauss–Newton information of the refine model and each point's
  marginal covariance (Schur complement over the motion), without Ceres. Used by refineWindow()
  for sigma_zc at its solution and by depthCramerRao() at the truth.
*/
#include "refine_model.h"

#include <Eigen/Core>
#include <array>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {
namespace refine_detail {

/*! One observation in the model: point index, motion-log row, whitened measurement. */
struct ModelObservation {
  int point = 0;
  int row = 0;
  WhitenedObservation w;
};

/*!
  The refine model at one value of its parameters (the solution, or the truth for the bound).
  Frame 0's pose is known (the gauge). Poses are free when odometry noise is modelled
  (sigma_odom > 0 or sigma_heading > 0), yaws when sigma_yaw > 0; otherwise they are known.
*/
struct Model {
  double t0[3] = {0, 0, 0};
  std::vector<std::array<double, 4>> poses; //!< per row
  std::vector<double> yaws;                 //!< per row
  std::vector<std::array<double, 3>> points;
  std::vector<int> anchor_row, report_row;  //!< per point
  std::vector<ModelObservation> observations;
  std::vector<OdometryMeasurement> odometry; //!< per row >= 1 (index row - 1); only sigmas used here
  double inv_sigma_yaw = 0;
  bool poses_free = false, yaws_free = false;

  int rows() const { return static_cast<int>(poses.size()); }
  /*! Index of a row's pose (4 values) among the motion parameters, or -1 when known. */
  int poseIndex(int row) const { return poses_free && row > 0 ? 4 * (row - 1) : -1; }
  /*! Index of a row's yaw among the motion parameters, or -1 when known. */
  int yawIndex(int row) const { return yaws_free ? (poses_free ? 4 * (rows() - 1) : 0) + row : -1; }
  int motionParameters() const { return (poses_free ? 4 * (rows() - 1) : 0) + (yaws_free ? rows() : 0); }
};

/*!
  Each point's covariance of its camera-frame position at its report row, from the inverse of the
  Gauss–Newton information of the whole model (joint = true: all points and the motion together)
  or of each point alone with the motion (joint = false). ok[i] is false when the point's own
  information is numerically singular (cov[i] is then NaN).
*/
void pointCovariances(const Model &model, bool joint, std::vector<Eigen::Matrix3d> &cov, std::vector<char> &ok);

/*! Whitening of an observation at undistorted point m with undistortion Jacobian J = d(x,y)/d(u,v). */
WhitenedObservation whitenObservation(const Eigen::Vector2d &m, const Eigen::Matrix2d &J, double sigma_px);

/*! The camera's rotation Ry(heading + yaw) and centre p + R t0 in the world. */
void cameraInWorld(const double *pose, double yaw, const Eigen::Vector3d &t0, Eigen::Matrix3d &R, Eigen::Vector3d &c);

/*! The measured increment between two motion-log rows (the priors). */
OdometryMeasurement measuredIncrement(const MotionSample &prev, const MotionSample &cur, const NoiseModel &noise);

/*! Lower bounds used instead of a zero sigma for a parameter that is estimated. */
constexpr double kMinSigmaLength = 1e-9; // m
constexpr double kMinSigmaAngle = 1e-9;  // rad
constexpr double kMinSigmaPx = 1e-6;     // px

} // namespace refine_detail
} // namespace yawdepth
