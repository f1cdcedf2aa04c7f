#pragma once
/*!
  \file depth_filter.h
  \brief `fused`: a recursive per-feature depth filter, updated frame by frame in O(1).

  State of one feature at the current frame k (camera frame, log inverse-depth parametrisation):
  \f[ s_k = (x, y, \lambda, e_k),\qquad \lambda = \log(1/Z_c),\qquad P_c = (x, y, 1)\, e^{-\lambda} \f]
  where \f$(x, y)\f$ is the feature's normalised position and \f$e_k\f$ the error of the current
  yaw reading (true yaw = reading + \f$e_k\f$). Each new frame brings one odometry increment and
  one observation:
  - prediction through the increment, rotation included: with \f$\rho = e^{\lambda}\f$,
    \f$ q = R(n)\,(x, y, 1)^T + \rho\, t(n),\ (x', y', \lambda') = (q_1/q_3,\ q_2/q_3,\ \lambda - \log q_3) \f$,
    with \f$ n = (\delta d, \delta\omega, e_k, e_{k+1}) \f$ the increment's translation and
    rotation noise (for a planar log only the heading, \f$\delta\omega_y\f$) and both yaw-reading errors (see yawdepth/geometry/rig.h). The yaw error of the earlier
    frame is carried in the state because consecutive increments share that reading: it is what
    makes the filter's odometry model exact rather than an inflated process noise.
  - update with the observed normalised point, which is linear in the state; the prediction's
    nonlinearity in \f$\lambda\f$ is handled by iterating the linearisation point of the joint
    (state, noise) Gaussian (an iterated EKF), so a diffuse depth prior is safe.
  - outliers: an observation whose innovation exceeds the chi-square gate is rejected; after
    `max_consecutive_outliers` rejections in a row the filter restarts at the current observation
    (the track jumped to another point).
  Why log inverse depth: odometry translation noise moves the image by an amount proportional to
  \f$\rho\f$ (near points move more), a multiplicative noise. In \f$\rho\f$ the filter's
  linearised noise then depends on its own error and it becomes overconfident where translation
  noise dominates (front view: 2-sigma coverage fell to 70 %); in \f$\log\rho\f$ the same noise
  is additive and the filter stays consistent. The depth is positive by construction.
  Weighting by parallax is implicit: an increment that moves the feature little along the
  epipolar direction carries little information about the depth and moves the estimate little.
  This is the Kalman form of Matthies–Kanade–Szeliski's depth filter, with the robot's noise
  sources modelled instead of a tuned process noise.
*/
#include <Eigen/Core>
#include <array>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*!
  \brief One odometry increment between consecutive motion-log rows, \f$ P_{cur} = R P_{prev} + t \f$,
  with the first-order sensitivity of R and t to the increment's noisy inputs, in the order
  (d_x, d_y, d_z, rot_x, rot_y, rot_z, yaw_prev, yaw_cur) (see IncrementPerturbation; rot_y is a
  planar log's heading). Computed once per frame, shared by every feature.
*/
struct IncrementModel {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity(); //!< rotation from the earlier to the later camera frame
  Eigen::Vector3d t = Eigen::Vector3d::Zero();     //!< translation from the earlier to the later camera frame (m)
  std::array<Eigen::Matrix3d, 8> dR;               //!< dR/d(input) for each noisy input, in the order above
  std::array<Eigen::Vector3d, 8> dt;               //!< dt/d(input) for each noisy input, in the order above
  bool six_dof = false; //!< from a 6-DoF log: the rotation is noisy about every axis, not only the heading
  long frame_prev = 0; //!< frame number of the earlier row
  long frame_cur = 0;  //!< frame number of the later row
  double yaw_cur = 0; //!< yaw reading of the later frame (rad)
  double distance = 0; //!< the vision frame's measured travel over the increment (m)
  double angle = 0;    //!< the vision frame's measured rotation over the increment (rad)
  /*! \brief The increment between two motion-log rows (prev before cur). */
  static IncrementModel between(const YawRig &rig, const MotionSample &prev, const MotionSample &cur);
};

/*!
  \brief A Gaussian prior on one increment's noise (d_x, d_y, d_z, rot_x, rot_y, rot_z, yaw of the
  later frame), the quantities the filter estimates along with the feature at each step. By default
  zero mean with the noise model's variances.
*/
struct IncrementPrior {
  Eigen::Matrix<double, 7, 1> mean = Eigen::Matrix<double, 7, 1>::Zero(); //!< prior mean of the increment noise
  Eigen::Matrix<double, 7, 7> cov = Eigen::Matrix<double, 7, 7>::Zero();  //!< prior covariance of the increment noise
};

/*!
  \brief Carry a composed motion's noise over one more increment (dead reckoning, first order).

  A motion \f$ [R | t] \f$ from a key frame to the current one, perturbed as IncrementPerturbation
  (translation \f$ e \f$ added in the key's frame, rotation \f$ r \f$ on the right), with covariance
  `cov` of \f$ (e, r) \f$, followed by one increment \f$ [\Delta R | d] \f$ (d in the current frame)
  whose own perturbation \f$ (e', r') \f$ has covariance Q, is perturbed by
  \f[ e'' = e - R [d]_\times r + R e', \qquad r'' = \Delta R^T r + r' \f]
  \param cov In: the covariance up to the current frame; out: up to the next one.
  \param R In: the current frame's rotation in the key's; out: the next frame's (R dR).
  \param d, dR The increment (m; rotation). \param Q The increment's 6x6 noise covariance.
*/
void composeIncrementNoise(Eigen::Matrix<double, 6, 6> &cov, Eigen::Matrix3d &R, const Eigen::Vector3d &d,
                           const Eigen::Matrix3d &dR, const Eigen::Matrix<double, 6, 6> &Q);

/*!
  \brief Relative half-width c of the depth interval \f$ [\hat Z (1 - c), \hat Z (1 + c)] \f$ that holds
  the depth with a Gaussian's 2-sigma probability (95.45 %) when the inverse depth is Gaussian with
  relative sigma r: \f$ \rho / \hat\rho \sim N(1, r^2) \f$. About 2r for small r, more for larger r
  (the far tail of Z = 1/rho is long): 0.61 at r = 0.2, 1.05 at r = 0.3. DepthFilter reports
  \f$ \sigma_Z = c \hat Z / 2 \f$. Infinity when no interval does (r above about 0.59: the
  inverse depth's own 2-sigma range reaches zero); NaN for a negative or non-finite r.
*/
double inverseDepthInterval(double r);

/*! \brief Whether inverseDepthInterval(r) is finite (the depth has a bounded 2-sigma interval: r below
    about 0.59), without computing the interval; false for a negative or non-finite r. */
bool inverseDepthBounded(double r);

/*! \brief The filter's own settings: its prior, outlier gate and convergence (no noise model: that is
    the caller's, DepthFilterOptions::noise or the options of whatever runs the filters). */
struct DepthFilterSettings {
  double prior_depth = 2.0;             //!< Prior median depth at the first observation (m).
  double prior_log_depth_sigma = 3.0;   //!< Prior sigma of log Z: diffuse (a factor e^3 = 20 per sigma).
  double outlier_chi2 = 13.8155;        //!< Innovation gate (chi-square, 2 dof; 99.9 %).
  int max_consecutive_outliers = 3;     //!< Restart after this many rejections in a row.
  int max_iterations = 10;              //!< Iterated-EKF iterations per update at most (1 = plain EKF); stops when converged.
  /*! Above this 1-sigma of log-depth the estimate is `degenerate`: the depth is not resolved
      (1.0: uncertain by a factor e = 2.7 either way; typical of features near the focus of expansion).
      Whatever this value, an estimate whose depth has no bounded 2-sigma interval (see
      inverseDepthInterval(): above about 0.59) is `degenerate`. */
  double max_log_depth_sigma = 1.0;
};

/*! \brief Options of DepthFilter: the noise model, the gates and the filter's settings. */
struct DepthFilterOptions : DepthFilterSettings {
  NoiseModel noise;  //!< Odometry and yaw noise (pixel noise comes with each observation).
  GateOptions gates; //!< no_motion and degenerate gates (on the whole track).
};

/*! \brief Recursive log-inverse-depth filter for one feature (the `fused` method). */
class DepthFilter {
public:
  using Options = DepthFilterOptions; //!< The filter's options.

  /*! \brief What a step did with its observation. */
  enum class Update { Inlier, Outlier, Restarted, PredictOnly };

  /*!
    \param options The filter's options.
    \param kx, ky Focal lengths (px), to express parallax in pixels for the degenerate gate.
  */
  explicit DepthFilter(const Options &options = Options(), double kx = 1.0, double ky = 1.0);

  /*!
    \brief Start at a first observation.
    \param frame Frame number. \param yaw Yaw reading of that frame (rad).
    \param m Observed normalised (undistorted) point. \param m_cov Its 2x2 covariance.
  */
  void initialize(long frame, double yaw, const Eigen::Vector2d &m, const Eigen::Matrix2d &m_cov);
  /*! \brief Whether initialize() was called (the filter has a state). */
  bool initialized() const { return initialized_; }

  /*!
    \brief Advance to the next frame through one increment, and update with its observation if any.
    \param inc The increment from the filter's current frame to the next (frame_prev must match).
    \param m, m_cov The next frame's observation, or nullptr when the feature was not observed.
    \param prior Prior on the increment's noise, or nullptr for defaultPrior().
    \return What happened to the observation. Throws yawdepth::Error when not initialised or when
            `inc` does not start at the filter's frame.
  */
  Update step(const IncrementModel &inc, const Eigen::Vector2d *m = nullptr, const Eigen::Matrix2d *m_cov = nullptr,
              const IncrementPrior *prior = nullptr);

  /*!
    \brief The noise model's prior on an increment (zero mean).
    \param six_dof from a 6-DoF log. \param distance the vision frame's travel over the increment (m)
    \param angle its rotation (rad): they scale the noise model's per-metre and per-radian terms.
  */
  IncrementPrior defaultPrior(bool six_dof = false, double distance = 0.0, double angle = 0.0) const;

  /*! \brief The point at the filter's current frame, with status (see the class description). */
  PointEstimate estimate(const YawRig &rig) const;

  /*! \brief Current depth estimate exp(-lambda) (m). */
  double depth() const { return std::exp(-s_(2)); }
  /*! \brief 1-sigma of log-depth: the relative depth uncertainty. */
  double logDepthSigma() const { return std::sqrt(P_(2, 2)); }
  /*! \brief The filter's current frame. */
  long frame() const { return frame_; }
  int inliers() const { return inliers_; }   //!< Observations used, the first one included.
  int outliers() const { return outliers_; } //!< Observations rejected since the last (re)start.
  double parallaxPx() const { return parallax_px_; } //!< Largest rotation-compensated parallax so far (px).

private:
  // The tests read the raw state (modules/estimation/src/depth_filter_test_access.h, not installed).
  friend struct DepthFilterTestAccess;
  Options o_;
  double kx_, ky_;
  bool initialized_ = false;
  long frame_ = 0;
  double yaw_ = 0;
  Eigen::Vector4d s_ = Eigen::Vector4d::Zero();
  Eigen::Matrix4d P_ = Eigen::Matrix4d::Zero();
  int inliers_ = 0, outliers_ = 0, consecutive_outliers_ = 0;
  long rejected_ = 0; // observations rejected since the filter was created (restarts included)
  // Geometry since the first observation: its bearing rotated into the current frame, and the
  // first optical centre in the current frame (for the parallax and baseline gates).
  Eigen::Vector3d anchor_bearing_ = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d anchor_centre_ = Eigen::Vector3d::Zero();
  double parallax_px_ = 0, baseline_ = 0;
};

} // namespace yawdepth
