#pragma once
/*!
  \file types.h
  \brief Observations in, point estimates out: the types every yawdepth estimator shares.
*/
#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <string>
#include <vector>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpMatrix.h>

namespace yawdepth {

/*! \brief One observation of a feature: its observed (distorted) pixel in a frame. */
struct Observation {
  long frame = 0; //!< frame number
  double u = 0;   //!< observed pixel: column (px)
  double v = 0;   //!< observed pixel: row (px)
};

/*!
  \brief One feature seen in one frame: its id and observed (distorted) pixel. What a detector or
  tracker returns per image (the ids of a pattern are in features/pattern.h), and what
  FusedEstimator, WindowEstimator and DepthProvider take per frame.
*/
struct FeatureObservation {
  long id = 0;  //!< feature id
  double u = 0; //!< observed pixel: column (px)
  double v = 0; //!< observed pixel: row (px)
};

/*! \brief Every observation of one feature, sorted by frame. */
struct Track {
  long id = 0;                           //!< feature id
  std::vector<Observation> observations; //!< sorted by frame
};

/*!
  \brief Why an estimate is or is not valid. Written in files as the word of toString().
*/
enum class Status {
  Ok,              //!< "ok": a valid estimate.
  Degenerate,      //!< "degenerate": too little parallax (feature near the focus of expansion).
  Behind,          //!< "behind": the depth at either frame is not positive.
  NoMotion,        //!< "no_motion": the camera did not translate (baseline below the gate).
  TooFewFrames,    //!< "too_few_frames": the feature was seen in fewer than two frames.
  UndistortFailed, //!< "undistort_failed": a pixel lies outside the distortion model's valid range.
  Unavailable,     //!< "unavailable": the method is not built in (e.g. Ceres missing).
  /*! "inconsistent": seen in enough frames, but its observations disagree with each other under the
      noise model (every one after the first rejected as an outlier): the noise model is too tight
      for the data, or the track is not one point. */
  Inconsistent
};

/*! \brief The status word used in files: "ok", "degenerate", "behind", "no_motion", ... */
const char *toString(Status s);
/*! \brief Parse a status word; throws yawdepth::Error for an unknown word. */
Status statusFromString(const std::string &word);

/*!
  \brief The estimation methods, cheapest first: the `--method` words of `yawdepth estimate`.
  yawdepth::estimatePoints() (yawdepth/pipeline/pipeline.h) runs any of them; estimateTracks()
  (yawdepth/estimation/track_estimator.h) the first three.
*/
enum class Method {
  Paper,  //!< "paper": eq. (5)-(7) on the last increment, as published.
  Exact,  //!< "exact": finite-increment two-view form on the last increment, rotation compensated.
  Fused,  //!< "fused": a recursive inverse-depth filter per feature over every frame (FusedEstimator).
  Window, //!< "window": every point with the last frames' motion, older frames marginalised (WindowEstimator).
  Refine  //!< "refine": joint MAP of every point with the motion over all frames (Ceres), started from fused.
};

/*! \brief "paper", "exact", "fused", "window", "refine". */
const char *toString(Method m);
/*! \brief Parse a method word; throws yawdepth::Error for an unknown one. */
Method methodFromString(const std::string &word);

/*! \brief The methods that estimate each track on its own from the whole log (estimateTracks()). */
enum class TrackMethod {
  Paper = static_cast<int>(Method::Paper), //!< Method::Paper
  Exact = static_cast<int>(Method::Exact), //!< Method::Exact
  Fused = static_cast<int>(Method::Fused)  //!< Method::Fused
};
/*! \brief The methods that run frame by frame (StreamEstimator, DepthProvider). */
enum class StreamMethod {
  Fused = static_cast<int>(Method::Fused),  //!< Method::Fused
  Window = static_cast<int>(Method::Window) //!< Method::Window
};
/*! \brief The same method in the whole set. */
Method toMethod(TrackMethod m);
/*! \brief The same method in the whole set. */
Method toMethod(StreamMethod m);
/*! \brief The method's word ("paper", "exact", "fused"). */
const char *toString(TrackMethod m);
/*! \brief The method's word ("fused", "window"). */
const char *toString(StreamMethod m);
/*! \brief Parse "paper", "exact" or "fused"; throws yawdepth::Error for any other word, naming it. */
TrackMethod trackMethodFromString(const std::string &word);
/*! \brief Parse "fused" or "window"; throws yawdepth::Error for any other word, naming it. */
StreamMethod streamMethodFromString(const std::string &word);

/*! \brief Whether the method models the tracker's correlated errors (NoiseModel::pixel_correlation):
    window and refine; the others take only 0. */
bool modelsTrackerCorrelation(Method m);

/*!
  \brief A point estimate with its uncertainty.

  Valid (finite) only when `status == Status::Ok`; otherwise the numbers are NaN.
*/
struct PointEstimate {
  Status status = Status::TooFewFrames; //!< Whether the estimate is valid, and why not.
  long frame = 0;                 //!< Frame the point is expressed at (the last observation).
  Eigen::Vector3d c_P = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
                                  //!< (Xc, Yc, Zc) in the camera frame at `frame` (m).
  Eigen::Vector3d v_P = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
                                  //!< (X, Y, Z) in the vision frame at `frame`, eq. (7) (m).
  Eigen::Matrix3d c_cov = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
                                  //!< First-order covariance of c_P (m^2).
  double parallax_px = std::numeric_limits<double>::quiet_NaN(); //!< Parallax used by the gate (px).

  /*! \brief `status == Status::Ok`: the estimate is valid. */
  bool ok() const { return status == Status::Ok; }
  /*! \brief 1-sigma depth uncertainty \f$ \sqrt{\Sigma_{ZZ}} \f$ (m). */
  double sigmaZ() const { return std::sqrt(c_cov(2, 2)); }
  /*! \brief c_P as a ViSP column vector (Xc, Yc, Zc). */
  vpColVector cP() const;
  /*! \brief v_P as a ViSP column vector (X, Y, Z). */
  vpColVector vP() const;
  /*! \brief c_cov as a ViSP matrix. */
  vpMatrix covariance() const;
};

/*!
  \brief How the motion log's poses err (NoiseModel::motion_noise).
*/
enum class MotionNoise {
  /*! Odometry, visual-inertial odometry: each frame-to-frame increment errs independently, so the
      poses' errors accumulate (dead reckoning). `sigma_odom`, `sigma_heading`, `sigma_rot` are per increment. */
  Increment,
  /*! Forward kinematics, motion capture: each row's pose errs independently about the truth, and the
      errors do not accumulate. `sigma_odom` and `sigma_rot` (`sigma_heading` for a planar log) are
      per pose; the per-metre and per-radian terms must be 0. */
  Absolute
};

/*! \brief "increment" or "absolute". */
const char *toString(MotionNoise m);
/*! \brief Parse "increment" or "absolute"; throws yawdepth::Error otherwise. */
MotionNoise motionNoiseFromString(const std::string &word);

/*! \brief Largest NoiseModel::pixel_correlation: beyond it an error is a drift, not noise (a track's
    innovations would weigh over seven times its first observation). */
constexpr double kMaxPixelCorrelation = 0.99;

/*! \brief The smallest pixel noise and robust scale (px) the methods that weigh every observation by
    them accept (fused, window, refine): zero or a denormal gives infinite weights and NaN sigmas. */
constexpr double kMinWeightPx = 1e-6;

/*!
  \brief Noise model of the inputs (1-sigma), used for uncertainty and for weighting.
*/
struct NoiseModel {
  double sigma_px = 0.3;            //!< Pixel noise per coordinate of an observation (px).
  double sigma_odom = 1e-3;         //!< Translation noise per frame-to-frame increment, per axis (m).
  double sigma_heading = 0.05 * M_PI / 180.0; //!< Heading noise per increment (rad), planar logs; 0.05 degree.
  double sigma_yaw = 0.05 * M_PI / 180.0;     //!< Noise of each yaw reading (rad); 0.05 degree.
  double sigma_rot = 0.05 * M_PI / 180.0;     //!< Rotation noise per increment per axis (rad), 6-DoF logs; 0.05 degree.
  /*! Translation noise per metre travelled, per axis (m/m): odometry's drift, whatever the step.
      Adds \f$ (\text{odom\_per\_metre}\, d)^2 \f$ to the variance of an increment of length d. */
  double odom_per_metre = 0.0;
  /*! Rotation noise per radian turned (rad/rad), on the noisy axes (the heading of a planar log, every
      axis of a 6-DoF log). Adds \f$ (\text{rot\_per\_radian}\, \theta)^2 \f$ for an increment turning by theta. */
  double rot_per_radian = 0.0;
  /*! Rotation noise per metre travelled (rad/m), on the noisy axes (wheel slip turns the heading). */
  double rot_per_metre = 0.0;
  /*! How the motion log's poses err: per increment (odometry, the default) or per pose (kinematics). */
  MotionNoise motion_noise = MotionNoise::Increment;
  /*! The tracker's errors from one image of a track to the next: an AR(1) process per pixel axis,
      \f$ e_k = \phi^{g} e_{k'} + \sqrt{1 - \phi^{2g}}\, \sigma_{px} n_k \f$ (k' the track's previous
      observation, g the frames between them, n white), stationary 1-sigma sigma_px. 0 (the default):
      independent errors, as a detector that finds each corner anew (a board) makes them; a tracker
      that follows a corner from image to image makes errors that persist (estimatePoints() may
      measure phi from the residuals for `window` and `refine`: modelsTrackerCorrelation()). At most 0.99. */
  double pixel_correlation = 0.0;
  /*! \brief Throws yawdepth::Error unless every sigma is finite and non-negative (and the per-metre
      and per-radian terms are 0 for MotionNoise::Absolute). */
  void validate() const;
  /*! \brief validate(), and what method `m` needs of the model: a pixel noise of at least
      kMinWeightPx for the methods that weigh every observation by it (fused, window, refine), and
      pixel_correlation 0 for a method that does not model it (modelsTrackerCorrelation()). */
  void validateFor(Method m) const;
};

/*!
  \brief The correlation of a tracker's errors between two observations of a track `gap` frames apart,
  under NoiseModel::pixel_correlation `phi`: \f$ \phi^{gap} \f$; 0 (no link) when phi or gap is not positive.
*/
double pixelCorrelationOver(double phi, long gap);

/*!
  \brief 1-sigma of one increment's translation noise per axis (m): the per-increment term and the
  per-metre term of an increment of length `distance` (m), added in variance; for
  MotionNoise::Absolute, sqrt(2) sigma_odom (two independent pose errors; consecutive increments
  then share one and are correlated, which an estimator that treats them as independent ignores).
*/
inline double incrementTranslationSigma(const NoiseModel &noise, double distance = 0.0)
{
  if (noise.motion_noise == MotionNoise::Absolute) // the difference of two independent pose errors
    return std::sqrt(2.0) * noise.sigma_odom;
  return std::hypot(noise.sigma_odom, noise.odom_per_metre * distance);
}

/*!
  \brief 1-sigma of one pose's rotation error per axis for MotionNoise::Absolute (rad): \f$ (0, \sigma_h, 0) \f$
  for a planar log, \f$ (\sigma_r, \sigma_r, \sigma_r) \f$ for a 6-DoF log.
*/
inline Eigen::Vector3d poseRotationSigma(const NoiseModel &noise, bool six_dof)
{
  return six_dof ? Eigen::Vector3d::Constant(noise.sigma_rot) : Eigen::Vector3d(0.0, noise.sigma_heading, 0.0);
}

/*!
  \brief 1-sigma of the rotation perturbation of one increment (IncrementPerturbation::d_rotation),
  per axis of the later vision frame: \f$ (0, \sigma_h, 0) \f$ for a planar log (only the heading
  is noisy), \f$ (\sigma_r, \sigma_r, \sigma_r) \f$ for a 6-DoF log; with the per-radian and per-metre
  terms of an increment that turns by `angle` (rad) over `distance` (m) added in variance.
*/
inline Eigen::Vector3d incrementRotationSigma(const NoiseModel &noise, bool six_dof, double distance = 0.0,
                                              double angle = 0.0)
{
  if (noise.motion_noise == MotionNoise::Absolute)
    return std::sqrt(2.0) * poseRotationSigma(noise, six_dof);
  const double grow = std::hypot(noise.rot_per_radian * angle, noise.rot_per_metre * distance);
  return six_dof ? Eigen::Vector3d::Constant(std::hypot(noise.sigma_rot, grow))
                 : Eigen::Vector3d(0.0, std::hypot(noise.sigma_heading, grow), 0.0);
}

/*!
  \brief Gates that turn bad geometry into a status word instead of a wrong number.
*/
struct GateOptions {
  /*! Camera translation between the two frames below this is `no_motion` (m). */
  double min_baseline = 1e-6;
  /*! Parallax below this is `degenerate` (px). Parallax is the image distance between the observed
      point and where a point at infinity would be after the known rotation; it vanishes at the
      focus of expansion. */
  double min_parallax_px = 0.02;
  /*! Throws yawdepth::Error unless both thresholds are finite and non-negative. */
  void validate() const;
};

} // namespace yawdepth
