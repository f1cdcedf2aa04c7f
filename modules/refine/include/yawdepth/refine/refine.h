#pragma once
/*!
  \file refine.h
  \brief `refine`: maximum a posteriori refinement of every point together with the odometry and
  yaw readings over a window of frames (a bundle adjustment with odometry factors), with Ceres.

  Parameters (all in the motion log's world frame, metres and radians):
  - per frame k >= 1: the vision-frame pose (x, y, z, heading); frame 0's pose is held fixed at
    the motion log's first row (it defines the world, as dead reckoning does);
  - per frame k: the yaw;
  - per point: anchored inverse depth (alpha, beta, rho) in the camera frame of the point's first
    observation, \f$ P = (\alpha, \beta, 1)/\rho \f$ (well conditioned for far points).
  Residuals (each whitened by its noise, so the cost is a negative log-likelihood):
  - every observation: the reprojection error in undistorted normalised coordinates, whitened by
    the pixel noise mapped through the undistortion Jacobian (so it is in units of sigma_px);
    with a robust loss whose threshold is `robust_threshold_px`;
  - every increment: measured minus estimated increment (translation in the earlier vision frame,
    `sigma_odom` per axis; heading change, `sigma_heading`; with the per-metre and per-radian terms
    of the noise model); or, for per-pose noise (NoiseModel::motion_noise = MotionNoise::Absolute:
    forward kinematics, motion capture), every pose: measured minus estimated pose (`sigma_odom`
    per axis, rotation `sigma_rot` per axis or the heading `sigma_heading`), and then frame 0 is
    estimated too (the log's world is kept by the priors, not by a gauge row);
  - every frame: measured minus estimated yaw (`sigma_yaw`).
  After the robust solve, observations whose reprojection error exceeds `outlier_threshold_px`
  are flagged and the problem is solved again without them and without the robust loss, so that
  the estimate is efficient on the inliers. The covariance of each point's camera-frame position
  at its last observed frame comes from the inverse of the Gauss–Newton information at the
  solution (marginalised with the Schur complement over the poses and yaws, the same as
  ceres::Covariance would give), propagated through that point's pose chain.

  Solve: the points start from `initial` (or `exact`, see refineWindow()); a Cauchy-loss solve,
  then the flagging, then the final least-squares solve on the inliers, both with Levenberg–Marquardt
  and the Schur complement (points eliminated first). In the Ceres problem each motion-log row is
  one parameter block (x, y, z, heading, yaw), with frame 0's pose held by a subset manifold; this
  is the same parametrisation as above, grouped so that the reduced system has few blocks.
  Per-track status after the final solve (on its inlier observations and the refined motion):
  `too_few_frames` (fewer than two observations, or fewer than two inliers), `undistort_failed`,
  `no_motion` (camera centre moved less than gates.min_baseline between the first and last inlier),
  `degenerate` (largest rotation-compensated parallax between the first inlier and a later one
  below gates.min_parallax_px, or the point's information numerically singular — the latter is
  only checked when compute_covariance is true), `behind` (depth at the first or last frame not
  positive), else `ok`. Tracks gated before the solve (on the measured motion) do not take part.

  Built only when Ceres is found (CMake option YAWDEPTH_WITH_CERES); otherwise refineAvailable()
  is false and refineWindow() returns status `unavailable` for every point.
*/
#include <Eigen/Core>
#include <functional>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/geometry/track_inputs.h>

namespace yawdepth {

/*! \brief Where a refineWindow() call is, for a progress line on long solves (RefineOptions::progress). */
struct RefineProgress {
  /*! \brief The step under way. */
  enum class Stage {
    RobustSolve, //!< the Cauchy-loss solve (iteration and cost are the solver's)
    FinalSolve,  //!< the least-squares solve on the inliers
    Covariance   //!< every point's covariance (called once, before it starts)
  };
  Stage stage = Stage::RobustSolve; //!< the step under way
  int iteration = 0;                //!< solver iteration within the step (0: its start)
  double cost = 0;                  //!< the solver's cost at that iteration (0 for Covariance)
  double seconds = 0;               //!< wall-clock time since refineWindow() started (s)
  int points = 0;                   //!< points taking part in the solve
  int frames = 0;                   //!< motion-log rows
};

/*! \brief Options of refineWindow(). */
struct RefineOptions {
  NoiseModel noise;                  //!< Noise of pixels, increments and yaw readings.
  GateOptions gates;                 //!< no_motion / degenerate gates (as `exact`, on the whole track).
  double robust_threshold_px = 1.0;  //!< Scale of the robust (Cauchy) loss, in pixels.
  double outlier_threshold_px = 2.0; //!< Observations with a larger reprojection error are flagged (px).
  int max_iterations = 50;           //!< Ceres iterations per solve.
  bool compute_covariance = true;    //!< Compute each point's covariance (sigma_zc).
  int threads = 1;                   //!< Ceres threads (the Jacobians and the linear solves).
  /*! Called as refine goes: after each solver iteration and before the covariances, on the
      calling thread; empty (the default): not called. The library itself never prints. */
  std::function<void(const RefineProgress &)> progress;
  /*! \brief Throws yawdepth::Error for a bad noise model (NoiseModel::validateFor()) or gate, a robust
      threshold under kMinWeightPx, an outlier threshold that is not positive, negative max_iterations or fewer
      than one thread. */
  void validate() const;
};

/*! \brief Result of refineWindow(). */
struct RefineResult {
  bool available = false;                  //!< false when built without Ceres.
  std::vector<PointEstimate> points;       //!< One per input track, same order, at the track's last frame.
  std::vector<std::vector<bool>> outliers; //!< Per track, per observation: flagged as an outlier.
  std::vector<MotionSample> motion;        //!< Refined motion-log rows (same frames as the input).
  int iterations = 0;                      //!< Ceres iterations, all solves together.
  double initial_cost = 0;                 //!< Initial cost of the final (inlier, non-robust) solve.
  double final_cost = 0;                   //!< Final cost of the final (inlier, non-robust) solve.
  bool converged = false;                  //!< Ceres reported convergence of the final solve.
};

/*! \brief Whether this build has the Ceres refinement. */
bool refineAvailable();

/*!
  \brief Refine every track's point jointly with the motion.
  \param camera Camera model (observed pixels are undistorted with it).
  \param rig Yaw rig.
  \param motion Motion-log rows. \param tracks The features; tracks with fewer than two observations
         get `too_few_frames`. The two must obey yawdepth::validateInputs()'s rules.
  \param initial An initial estimate per track (e.g. from `fused`), same order as `tracks`, used
         when its status is ok; other tracks start from `exact` on their first and last frames or,
         failing that, from the median depth of the others. May be empty (no initial estimates).
         Each track's candidates (the given estimate, `exact` on its first/second and
         second-to-last/last observations) are scored robustly against all its observations and
         the best one is used, so one gross error at either end does not spoil the start.
  \param options Noise model, robust loss and solver options.
  \throws yawdepth::Error for inconsistent input (sizes, validateInputs()'s rules).
*/
RefineResult refineWindow(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                          const std::vector<Track> &tracks, const std::vector<PointEstimate> &initial,
                          const RefineOptions &options = RefineOptions());

/*!
  \brief refineWindow() on input already validated (yawdepth::validateInputs(): what
  yawdepth::estimatePoints() passes); the same results.
*/
RefineResult refineWindow(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                          const std::vector<PointEstimate> &initial, const RefineOptions &options = RefineOptions());

/*!
  \brief Cramér–Rao lower bound of each point's depth zc at its track's last frame.

  The Fisher information of the same model as refineWindow() (pixels of every observation in
  `tracks`, their errors an AR(1) process along each track when noise.pixel_correlation > 0, priors
  on every increment (or pose) and yaw reading; for increment noise frame 0's pose known), evaluated
  at the truth, inverted, and projected on the depth. Only the frames of the observations are used, not
  their pixel values. Returns the 1-sigma bound per track (NaN for tracks with < 2 observations).
  \param camera Camera model. \param rig Yaw rig.
  \param truth True motion rows. \param tracks The features (only their observations' frames are used).
  \param w_points True points in the world frame, one per track.
  \param noise Pixel, odometry and yaw noise.
  \param joint true: all points and the motion estimated together (the bound for `refine`);
         false: each point alone with the motion (the bound for a per-feature method).
*/
std::vector<double> depthCramerRao(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &truth,
                                   const std::vector<Track> &tracks, const std::vector<Eigen::Vector3d> &w_points,
                                   const NoiseModel &noise, bool joint = true);

} // namespace yawdepth
