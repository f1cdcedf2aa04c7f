#pragma once
/*
  The Gauss–Newton information of the measurement model (refine_model.h) and each point's marginal
  covariance (Schur complement over the motion), without Ceres (internal: modules/model, never
  installed; information.cpp is compiled into yawdepth_window's library). Used by yawdepth::refine:
  refineWindow() for sigma_zc at its solution and depthCramerRao() at the truth; and by
  yawdepth::window for the observations' whitening and the measured increments (whitenObservation,
  measuredIncrementGeneral, the pixel-noise floor kMinWeightPx), so that both estimators weigh the same measurements alike.
*/
#include "refine_model.h"

#include <Eigen/Core>
#include <array>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {
namespace refine_detail {

/* One observation in the model: point index, motion-log row, whitened measurement. */
struct ModelObservation {
  int point = 0;
  int row = 0;
  WhitenedObservation w;
};

/*
  The refine model at one value of its parameters (the solution, or the truth for the bound).
  Frame 0's pose is known (the gauge) for increment noise; with per-pose noise (absolute) every
  pose has its own prior and none is the gauge. Poses are free when odometry noise is modelled
  (sigma_odom > 0, or the rotation's sigma > 0), yaws when sigma_yaw > 0; otherwise they are known.
  Two chains (refine_model.h): planar (pose = x, y, z, heading; mount t0 only) and general (pose =
  x, y, z, d(3) about the row's reference orientation; any mount), where a planar log frees only
  the heading component dy.
*/
struct Model {
  bool general = false;
  double t0[3] = {0, 0, 0};                 // planar chain's mount
  Mount mount;                              // general chain's mount
  std::vector<std::array<double, 6>> poses; // per row: planar (x, y, z, heading, -, -), general (x, y, z, d)
  std::vector<Eigen::Matrix3d> Rref;        // per row, general chain
  std::vector<double> yaws;                 // per row
  std::vector<std::array<double, 3>> points;
  std::vector<int> anchor_row, report_row;  // per point
  std::vector<ModelObservation> observations;
  std::vector<OdometryMeasurement> odometry; // planar: per row >= 1 (index row - 1); only sigmas used here
  std::vector<OdometryMeasurementGeneral> odometry_general; // general: the same
  bool absolute = false;                    // per-pose motion noise: pose_priors instead of odometry, no gauge row
  std::vector<PosePrior> pose_priors;       // per row, when absolute
  double inv_sigma_yaw = 0;
  bool poses_free = false, yaws_free = false;
  bool rotation_free[3] = {false, true, false}; // general chain: which components of d are estimated
  // The tracker's correlated errors (NoiseModel::pixel_correlation; refine's costs/innovation_costs.h): per
  // observation, the index of its track's previous observation in the chain (same point, earlier
  // row) or -1, and the AR(1) coefficient a on it; the observation then enters as the innovation
  // (r - a r_prev) / sqrt(1 - a^2). Shorter than observations (empty: independent errors): -1 beyond.
  std::vector<int> chain_prev;
  std::vector<double> chain_a;

  int rows() const { return static_cast<int>(poses.size()); }
  /* The first row whose pose is estimated: 1 (row 0 is the gauge) for increment noise, 0 for per-pose noise. */
  int firstFreeRow() const { return absolute ? 0 : 1; }
  int poseDim() const { return general ? 6 : 4; }
  /* Index of component j of a row's pose among the motion parameters, or -1 when known. */
  int poseIndex(int row, int j) const;
  /* Index of a row's yaw among the motion parameters, or -1 when known. */
  int yawIndex(int row) const;
  int motionParameters() const;
  /* Estimated components per pose (rows >= firstFreeRow()). */
  int freePoseComponents() const;
  /* Whether component j of a pose is estimated (for rows >= 1, when poses are free). */
  bool componentFree(int j) const { return j < 3 || !general || rotation_free[j - 3]; }
  /* Links observation obs to prev (its chain's previous) with coefficient a, 0 < a < 1. */
  void setChainLink(std::size_t obs, std::size_t prev, double a);
  /* Observation obs's chain predecessor, or -1. */
  int chainPrevious(std::size_t obs) const { return obs < chain_prev.size() ? chain_prev[obs] : -1; }
};

/*
  Each point's covariance of its camera-frame position at its report row, from the inverse of the
  Gauss–Newton information of the whole model (joint = true: all points and the motion together)
  or of each point alone with the motion (joint = false). ok[i] is false when the point's own
  information is numerically singular (cov[i] is then NaN).
*/
void pointCovariances(const Model &model, bool joint, std::vector<Eigen::Matrix3d> &cov, std::vector<char> &ok);

/* Whitening of an observation at undistorted point m with undistortion Jacobian J = d(x,y)/d(u,v). */
WhitenedObservation whitenObservation(const Eigen::Vector2d &m, const Eigen::Matrix2d &J, double sigma_px);

/* The camera's rotation Ry(heading + yaw) and centre p + R t0 in the world (planar chain). */
void cameraInWorld(const double *pose, double yaw, const Eigen::Vector3d &t0, Eigen::Matrix3d &R, Eigen::Vector3d &c);
/* The camera's rotation and centre in the world (general chain; frame[7], see refine_model.h). */
void cameraInWorldGeneral(const double *frame, const Eigen::Matrix3d &Rref, const Mount &mount, Eigen::Matrix3d &R,
                          Eigen::Vector3d &c);

/* The measured increment between two motion-log rows (the priors), planar chain. */
OdometryMeasurement measuredIncrement(const MotionSample &prev, const MotionSample &cur, const NoiseModel &noise);
/* The measured increment between two motion-log rows, general chain (reference orientations: the rows'). */
OdometryMeasurementGeneral measuredIncrementGeneral(const MotionSample &prev, const MotionSample &cur,
                                                    const NoiseModel &noise);

/* Whether refine must use the general chain: a 6-DoF row, or a mount with a rotation. */
bool needsGeneralChain(const YawRig &rig, const std::vector<MotionSample> &motion);

/*
  The model's chain, mount, free parameters and motion priors for a rig and the measured motion log
  (the reference orientations are the measured rows'); poses, yaws and points are left to the caller
  (a planar pose is (x, y, z, heading), a general one (x, y, z, d) about Rref).
*/
void setModelMotion(Model &m, const YawRig &rig, const std::vector<MotionSample> &measured, const NoiseModel &noise);

/* Lower bounds used instead of a zero sigma for a parameter that is estimated. */
constexpr double kMinSigmaLength = 1e-9; // m
constexpr double kMinSigmaAngle = 1e-9;  // rad

} // namespace refine_detail
} // namespace yawdepth
