#pragma once
/*!
  \file depth_provider.h
  \brief Depth for ViSP's point features in a servo loop, from the robot's motion: no constant
  guess, no depth sensor.

  Each control period, give the provider the odometry (the vision frame's pose and the camera's
  yaw reading, a yawdepth::MotionSample) and the tracked points' observed pixels by id; then let it
  set the depth of your vpFeaturePoint's with apply(). By default it runs the `window` estimator
  (yawdepth::WindowEstimator: a sliding-window smoother of every tracked point with the recent
  motion, at the joint Cramér–Rao bound; pixel, odometry and yaw noise modelled); with
  `method = StreamMethod::Fused` the cheaper per-feature filter (yawdepth::FusedEstimator), which
  cannot tell the odometry's error from a feature's depth. It gives:

  - depth(id): the estimated depth Zc of the feature in the CURRENT camera frame once the estimate
    has converged (relative 1-sigma below `converged_relative_sigma`), otherwise the prior
    (`prior_depth`, 1 m like vpFeaturePoint's default, or a per-feature prior set by setPrior()).
    Once a feature has converged it keeps its estimate while the relative sigma stays below
    `release_factor` x the threshold (no flicker between prior and estimate). The value is always
    finite and within [min_depth, max_depth]: never the non-positive Z that vpFeaturePoint::set_Z()
    rejects.
  - sigma(id): the 1-sigma uncertainty of depth(id) (m): the estimate's, or for the prior
    `prior_depth * prior_relative_sigma`.
  - status(id): the estimator's status word (ok, too_few_frames, degenerate, no_motion, ...).
  - converged(id): whether depth(id) is the estimate (true) or the prior (false). The estimate is
    used once its relative sigma is below the threshold (the window estimator's sigma is consistent:
    2-sigma coverage 0.93-0.97 in bench_accuracy), and revoked when it jumps between two periods by
    more than `revoke_sigmas` combined sigmas; it is used again after `confirm_periods` periods
    without a jump. Each feature is judged on its own sigma: with the window estimator the
    features share the motion, so features seen as well converge together.

  The depth only matters when the interaction matrix is computed from the current features:
  use `task.setInteractionMatrixType(vpServo::CURRENT)` (or vpServo::MEAN). With vpServo::DESIRED
  the interaction matrix is built once from the desired features' depth and the current depths
  are never read.

  Observations are the observed (distorted) pixels, as a tracker gives them (vpImagePoint is
  (i = v, j = u)); the provider undistorts them with its camera model. vpFeaturePoint works on
  undistorted normalised coordinates: build them with buildFrom(), which undistorts the same way.

  Standing still must not count as motion: the noise model's odometry noise has a per-increment
  floor (and a log's noise model may be per increment only), so the provider feeds the estimator a
  new frame only once the camera has translated
  at least `min_translation` since the last frame it used (or after `max_skipped_periods`
  periods). In the periods in between, the estimates are carried to the current camera frame
  through the odometry, so depth(id) is always the depth at the latest update().

  Typical loop (see examples/servo_ibvs_yawing_camera.cpp):
  \code
  yawdepth::DepthProvider depth(camera, rig);        // camera: yawdepth::CameraModel or vpCameraParameters
  std::vector<vpFeaturePoint> s(4), sd(4);            // current and desired features
  task.setInteractionMatrixType(vpServo::CURRENT);    // depth matters only with CURRENT or MEAN
  for (;;) {
    // odometry: vision-frame pose (x, y, z, heading) and the pan angle; points: (id, observed pixel)
    depth.update(odometry, points);
    for (std::size_t i = 0; i < s.size(); ++i)
      depth.buildFrom(ids[i], pixel[i], s[i]);       // x, y undistorted, Z = depth(id)
    vpColVector qdot = task.computeControlLaw();
  }
  \endcode
  Library code: never prints; throws yawdepth::Error for invalid options or input.
*/
#include <limits>
#include <map>
#include <utility>
#include <vector>
#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/visual_features/vpFeaturePoint.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/window/stream_estimator.h>

namespace yawdepth {

/*!
  \brief The provider's default noise model: 0.3 px; odometry that drifts by 2 % of the distance
  travelled (per axis) and 2 % of the angle turned, plus 0.01 rad per metre (wheel slip), as wheel
  odometry and arm kinematics do over a control period, with a floor of 10 micrometres and 1e-5 rad per
  estimator increment; 0.05 degree per pan reading. Unlike the command line's per-increment
  defaults (for logs with a fixed frame spacing), it does not depend on how far the camera moves
  between two updates.
*/
inline NoiseModel servoNoiseModel()
{
  NoiseModel n;
  n.sigma_odom = 1e-5;
  n.sigma_heading = 1e-5;
  n.sigma_rot = 1e-5;
  n.odom_per_metre = 0.02;
  n.rot_per_radian = 0.02;
  n.rot_per_metre = 0.01;
  return n;
}

/*! \brief Options of DepthProvider. Lengths in m, angles in rad. */
struct DepthProviderOptions {
  double prior_depth = 1.0;              //!< Depth used until a feature's estimate converges (ViSP's default Z = 1 m).
  double prior_relative_sigma = 1.0;     //!< sigma(id) of the prior, relative to it (a guess: 100 %).
  double converged_relative_sigma = 0.10; //!< Use the estimate once sigma(Z)/Z is below this (10 %: IBVS tolerates such errors well).
  double release_factor = 2.0;           //!< Keep a converged estimate while sigma(Z)/Z < release_factor x the threshold.
  /*! Revoke convergence when the estimate moves between two periods by more than this many
      combined sigmas (sqrt(sigma_before^2 + sigma_now^2), the point carried through the odometry):
      a consistent estimate does not jump; one that does (a restart, an outlier flipped) is not
      trusted until it has held still again. */
  double revoke_sigmas = 4.0;
  int confirm_periods = 3;               //!< After a revocation, consistent periods needed before the estimate is used again (>= 1).
  double min_depth = 0.05;               //!< depth() never returns less (m); must be > 0.
  double max_depth = 100.0;              //!< depth() never returns more (m).
  double min_translation = 0.002;        //!< Feed the estimator once the camera moved this far (m).
  int max_skipped_periods = 50;          //!< ... or after this many periods (> 0), whatever the motion.
  /*! Pixel, odometry, heading and yaw noise; see servoNoiseModel(): the default odometry noise
      grows with the distance travelled and the angle turned, so it holds whatever the control
      period and min_translation. */
  NoiseModel noise = servoNoiseModel();
  double initial_depth = 0.0;            //!< Filter's initial median depth (m); 0 = prior_depth.
  /*! Forget a feature unseen for this many estimator frames (the window estimator keeps a feature
      in its state while it is seen within its window, restarts it when it comes back later, and
      drops what it kept of it after this many frames). */
  int max_missing_frames = 30;
  /*! The estimator, run through a StreamEstimator: `window` (WindowEstimator: every feature and the
      recent motion together, the default) or `fused` (FusedEstimator: one filter per feature,
      cheaper, several times less accurate). */
  StreamMethod method = StreamMethod::Window;
  int window = 10;                       //!< Frames in the window estimator's window (>= 2).
  /*! \brief Throws yawdepth::Error for an invalid option. */
  void validate() const;
};

/*! \brief Everything the provider knows about one feature's depth. */
struct FeatureDepth {
  long id = 0;          //!< feature id
  double depth = 1.0;   //!< What apply() sets: the estimate when converged, else the prior (m).
  double sigma = 1.0;   //!< 1-sigma of `depth` (m).
  bool converged = false; //!< `depth` is the estimate.
  Status status = Status::TooFewFrames; //!< The estimator's status.
  double estimate = std::numeric_limits<double>::quiet_NaN(); //!< The estimate at the current frame, converged or not (NaN unless status ok).
  double estimate_sigma = std::numeric_limits<double>::quiet_NaN(); //!< Its 1-sigma (m).
  long revocations = 0; //!< Times convergence was revoked because the estimate jumped (see revoke_sigmas).
};

/*! \brief Depth of vpFeaturePoint's from the robot's odometry and the image motion (see the file). */
class DepthProvider {
public:
  using Options = DepthProviderOptions; //!< The provider's options.

  /*!
    \param camera Camera model (distortion included); \param rig the yaw mechanism (optical centre offset).
    \param options The provider's options.
  */
  DepthProvider(const CameraModel &camera, const YawRig &rig, const Options &options = Options());
  /*! \brief Same, from ViSP camera parameters (with or without ViSP's kud distortion). */
  DepthProvider(const vpCameraParameters &camera, const YawRig &rig, const Options &options = Options());

  /*!
    \brief One control period: the odometry and the observed pixels of the tracked points.
    \param odometry Pose of the vision frame in the odometry's world frame (x, y, z, heading, or
           a 6-DoF MotionSample) and the camera's yaw reading; `odometry.frame` is ignored (the
           provider counts periods).
    \param points (id, observed pixel) of each tracked point, at most one per id. Points may come
           and go; a point not seen for `max_missing_frames` estimator frames is forgotten.
    Throws yawdepth::Error for a non-finite odometry or a repeated id.
  */
  void update(const MotionSample &odometry, const std::vector<std::pair<long, vpImagePoint>> &points);

  /*!
    \brief One control period of any robot: the pose of the vision frame in a fixed world frame as
    ViSP gives it (an arm's end-effector in its base, e.g. from vpRobot::getPosition(), or the
    camera itself with an identity `camera_pose`, e.g. vpSimulatorCamera::getPosition()), a 6-DoF
    sample with the rig's noise model `sigma_odom` and `sigma_rot` per update.
    \param wMv Pose of the vision frame in the world. \param points as above.
    \param yaw Pan reading when the vision frame carries a pan joint (rad), else 0.
  */
  void update(const vpHomogeneousMatrix &wMv, const std::vector<std::pair<long, vpImagePoint>> &points,
              double yaw = 0.0);

  /*! \brief Depth to use for feature `id` (m): see the file. Always in [min_depth, max_depth]. */
  double depth(long id) const;
  /*! \brief 1-sigma of depth(id) (m). */
  double sigma(long id) const;
  /*! \brief The estimator's status for `id` (too_few_frames for an unknown id). */
  Status status(long id) const;
  /*! \brief Whether depth(id) is the estimate (else the prior). */
  bool converged(long id) const;
  /*! \brief All of the above at once. */
  FeatureDepth info(long id) const;
  /*! \brief The full estimate (camera-frame point and covariance) at the current frame. */
  PointEstimate estimate(long id) const;

  /*! \brief A prior depth for one feature (m, > 0), e.g. from a known object size; replaces prior_depth for it. */
  void setPrior(long id, double Z);

  /*! \brief s.set_Z(depth(id)). */
  void apply(long id, vpFeaturePoint &s) const;
  /*! \brief set_Z for each feature: `features[i]` is feature `ids[i]` (sizes must match). */
  void apply(const std::vector<long> &ids, std::vector<vpFeaturePoint> &features) const;
  /*!
    \brief Build a feature from an observed pixel: undistorted normalised (x, y) by the provider's
    camera model and Z = depth(id). Throws yawdepth::Error when the pixel cannot be undistorted.
  */
  void buildFrom(long id, const vpImagePoint &observed, vpFeaturePoint &s) const;

  /*! \brief Number of update() calls so far. */
  long periods() const { return period_; }
  /*! \brief Number of frames given to the estimator (periods with enough motion). */
  long estimatorFrames() const { return frames_used_; }
  /*! \brief The camera model. */
  const CameraModel &camera() const { return camera_; }
  /*! \brief The yaw rig. */
  const YawRig &rig() const { return rig_; }
  /*! \brief The options. */
  const Options &options() const { return o_; }
  /*! \brief The estimator, frame by frame (its frames are the periods fed to it). */
  const StreamEstimator &stream() const { return stream_; }

private:
  void refresh(long id);
  double priorOf(long id) const;

  CameraModel camera_;
  YawRig rig_;
  Options o_;
  StreamEstimator stream_;
  std::map<long, long> last_seen_;        // estimator frame at which each id was last given
  long period_ = 0, frames_used_ = 0, skipped_ = 0;
  bool have_fed_ = false;
  MotionSample last_fed_, current_;
  std::map<long, double> priors_;
  std::map<long, FeatureDepth> state_;
  struct Consistency {                    // the last period's estimate, for the jump test
    bool has_prev = false;
    Eigen::Vector3d o_P_prev = Eigen::Vector3d::Zero(); // in the odometry world (m)
    double sigma_prev = 0;                // its depth sigma (m)
    int wait = 0;                         // periods still to hold still after a revocation
  };
  std::map<long, Consistency> consistency_;
};

} // namespace yawdepth
