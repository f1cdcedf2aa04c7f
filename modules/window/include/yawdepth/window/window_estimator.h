#pragma once
/*!
  \file window_estimator.h
  \brief `window`: a recursive estimator at the joint bound. A sliding-window smoother over the
  last K frames' poses and every tracked feature, with the older frames marginalised into a
  Gaussian prior; constant work per frame for a given number of features, no Ceres.

  What it estimates (all in the motion log's world frame, metres and radians):
  - per window frame k: the vision frame's position \f$ p_k \f$, its orientation
    \f$ V_k = R^{ref}_k \exp(d_k) \f$ about the row's measured orientation \f$ R^{ref}_k \f$, and
    the camera yaw; the camera is at \f$ {}^wR_c = V_k R_y(\text{yaw}_k) R_0 \f$,
    \f$ {}^wc = p_k + V_k R_y(\text{yaw}_k) t_0 \f$ with the mount \f$ (R_0, t_0) \f$ = vMc(0).
    A planar log estimates only \f$ d_y \f$ (the heading); the first frame's pose is held at its
    row (it defines the world, as dead reckoning does) unless the motion noise is per pose;
  - per feature: inverse depth \f$ (\alpha, \beta, \rho) \f$ anchored in a *fixed* world frame
    \f$ (R_a, c_a) \f$ (the estimate of the camera that first saw it, frozen as a constant):
    \f$ {}^wP = c_a + R_a (\alpha, \beta, 1)^T / \rho \f$. Because the anchor is not a state
    variable, dropping old frames never re-anchors a feature.

  Factors (whitened, so the cost is a negative log-likelihood): every observation's reprojection
  error in undistorted normalised coordinates (units of sigma_px, as in `refine`); every
  increment between consecutive frames (or every pose, for per-pose motion noise); every yaw
  reading; a weak prior on each feature's inverse depth (options.prior_inverse_depth,
  prior_sigma_inverse_depth: \f$ 10\,\text{m}^{-1} \f$ by default, under \f$ 10^{-5} \f$ of the
  information two frames 2 cm apart give a point at 3 m, so that a point without parallax stays finite).

  Each frame: the new frame's pose is aligned alone to the state (dead reckoning as the start),
  then Gauss–Newton runs on the whole window (the points eliminated by the Schur complement, a
  3 x 3 block each, and the reduced system of the poses factorised; chord steps reuse the last
  factorisation while they make progress; it stops when another step would lower the cost by less
  than `convergence`). Least squares first; when that changes an
  outlier flag (reprojection error beyond outlier_threshold_px), a Cauchy phase (scale
  robust_threshold_px) runs before the final least squares on the inliers, so that the estimate is
  efficient and the covariance is the inverse of the information. When the window holds more than
  `window` frames, the oldest is marginalised: its factors and the previous prior are linearised
  at the current estimate and the frame (with every feature no later frame of the window
  observed) is removed by the Schur complement. The prior holds no feature-feature term: what the
  removed frames coupled between features is carried by a few auxiliary directions, estimated with
  the state (the leading directions of that coupling in each feature's own information units;
  those dropped carry under 1 % of any feature's information). Every later Jacobian of a frame or feature in the
  prior is evaluated at the value it had when it entered the prior (first-estimate Jacobians), so
  that relinearisation cannot make the prior overconfident. Flags of the marginalised observations
  are final. A feature enters the state at its second observation within the window; its start is
  the best of candidates (the pairs of up to five of its observations, spread over the window,
  triangulated; their rays at the prior's depth), each refined alone with the robust loss and scored robustly against all its
  observations. A feature whose window observations are mostly flagged restarts from them (what
  the prior held on it is dropped). A single observation that leaves the window is dropped.

  Reported per feature: the point in the camera frame of its last observed frame and its
  covariance (the marginal of the point and that frame's pose, from the inverse information),
  with the gates of `refine`: `too_few_frames` (fewer than two inlier observations, or fewer than
  three when some were flagged: two observations always agree on a point, so two cannot tell
  which were the outliers),
  `undistort_failed`, `no_motion` (camera centre moved less than gates.min_baseline between the
  first and the last inlier), `degenerate` (largest rotation-compensated parallax below
  gates.min_parallax_px; or a depth without a bounded 2-sigma interval, as `fused`'s
  inverseDepthInterval(); or a non-positive inverse depth whose 2-sigma range reaches positive
  values), `behind` (the point behind a camera that saw it, or its inverse depth below zero by
  more than 2 sigma), else `ok`. A feature whose last observation left the window is
  removed from the state and its last estimate kept (estimate() returns it until forget()); if it
  is observed again it starts anew.

  Cost per frame: linear in the N features in the state, O(N (5K + A)^2) with K planar frames
  (7K for 6-DoF) and A auxiliary directions (at most 64); see docs/accuracy.md's cost table.
*/
#include <Eigen/Core>
#include <deque>
#include <map>
#include <memory>
#include <set>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/fused_estimator.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/geometry/track_inputs.h>

namespace yawdepth {

/*! \brief Options of WindowEstimator. */
struct WindowOptions {
  NoiseModel noise;                        //!< Noise of pixels, increments (or poses) and yaw readings.
  GateOptions gates;                       //!< no_motion / degenerate gates, as `refine`.
  int window = 10;                         //!< Frames kept in the window (>= 2).
  double robust_threshold_px = 1.0;        //!< Scale of the Cauchy loss (px).
  double outlier_threshold_px = 2.0;       //!< Observations with a larger reprojection error are flagged (px).
  int max_iterations = 4;                  //!< Gauss–Newton iterations per frame and phase (robust, then inliers).
  /*! Gauss–Newton stops when another iteration would lower the cost (chi^2 / 2) by less than this:
      0.1 leaves the estimate within about 0.45 sigma of the optimum along the worst direction (the
      remainder is carried into the next frame's solve, and into the prior exactly). */
  double convergence = 0.1;
  double prior_inverse_depth = 0.5;        //!< Mean of the weak inverse-depth prior (1/m).
  /*! Its sigma (1/m). It pulls an estimate by \f$ (\sigma_\rho / \sigma_{prior})^2 \f$ of its distance
      to the prior's mean (a few 1e-5 of the depth for a front-view point at 3 m, a small fraction of
      its sigma). */
  double prior_sigma_inverse_depth = 10.0;
  /*! \brief Throws yawdepth::Error for a bad value (window < 2, negative or non-finite values, ...). */
  void validate() const;
};

/*! \brief The sliding-window smoother; frames in, feature estimates out. */
class WindowEstimator {
public:
  using Options = WindowOptions; //!< The estimator's options.

  /*!
    \brief An estimator with no frame yet.
    \param camera Camera model (observed pixels are undistorted with it).
    \param rig Camera mount and yaw joint.
    \param options Noise, gates, window length. Throws yawdepth::Error if they are invalid.
  */
  WindowEstimator(const CameraModel &camera, const YawRig &rig, const Options &options = Options());
  ~WindowEstimator();
  WindowEstimator(const WindowEstimator &) = delete;
  WindowEstimator &operator=(const WindowEstimator &) = delete;
  /*! \brief Movable (the state moves with it). */
  WindowEstimator(WindowEstimator &&) noexcept;
  /*! \brief Movable (the state moves with it). */
  WindowEstimator &operator=(WindowEstimator &&) noexcept;

  /*! \brief What happened to one observation of the frame just added (flags may change later). */
  struct ObservationResult {
    long id = 0;             //!< feature id
    bool inlier = true;      //!< false: flagged as an outlier after this frame's solve
    bool undistorted = true; //!< false: outside the distortion model, not used
  };

  /*!
    \brief Add the next frame: its motion-log row and its observations (at most one per id; an id
    seen twice throws). Rows must have strictly increasing frame numbers and all be planar or all
    6-DoF (throws yawdepth::Error otherwise).
  */
  std::vector<ObservationResult> addFrame(const MotionSample &row, const std::vector<FeatureObservation> &observations);

  /*!
    \brief A feature's point at its last observed frame, with covariance and status. Unknown ids
    and features seen once get `too_few_frames`.
  */
  PointEstimate estimate(long id) const;
  /*! \brief Whether the observation of feature `id` at `frame` is (currently) flagged as an outlier. */
  bool isOutlier(long id, long frame) const;
  /*! \brief Ids of the features in the state (seen at least twice in the window, still tracked). */
  std::vector<long> ids() const;
  /*! \brief Forget a feature (in the state it is marginalised; its kept estimate and outlier flags
      are dropped). The kept estimates of features that left the state stay until then: a long-running
      caller forgets the ids it no longer tracks, as DepthProvider does. */
  void forget(long id);
  /*! \brief Frame of the last addFrame() (0 before the first). */
  long frame() const;
  /*! \brief Frames currently in the window. */
  int windowFrames() const;
  /*! \brief The estimated motion-log row of a frame still in the window (throws otherwise). */
  MotionSample motion(long frame) const;
  /*! \brief Parameters currently estimated: the frames' free components, 3 per feature in the
      state and the prior's auxiliary directions. */
  int stateDimension() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/*!
  \brief Run WindowEstimator over a motion log and tracks, the batch interface of the CLI and the
  benchmarks: every row is fed in order with the observations of that frame.
  \param camera, rig As for WindowEstimator.
  \param motion Motion-log rows. \param tracks The features. The two must obey
         yawdepth::validateInputs()'s rules (throws yawdepth::Error otherwise).
  \param options Estimator options.
  \param outliers If not null, receives per track and per observation whether it was flagged (the
         final flags).
  \return One estimate per track (same order), at the track's last observed frame.
*/
std::vector<PointEstimate> windowTracks(const CameraModel &camera, const YawRig &rig,
                                        const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                        const WindowOptions &options = WindowOptions(),
                                        std::vector<std::vector<bool>> *outliers = nullptr);

/*!
  \brief windowTracks() on input already validated (yawdepth::validateInputs(): what
  yawdepth::estimatePoints() passes); the same results.
*/
std::vector<PointEstimate> windowTracks(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                        const WindowOptions &options = WindowOptions(),
                                        std::vector<std::vector<bool>> *outliers = nullptr);

} // namespace yawdepth
