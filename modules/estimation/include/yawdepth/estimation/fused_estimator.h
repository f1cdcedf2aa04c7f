#pragma once
/*!
  \file fused_estimator.h
  \brief `fused` for many features at once: one DepthFilter per feature, advanced frame by frame.

  The frame-by-frame form of `fused` that a servo loop or a tracker calls: each frame brings the
  motion-log row and the observed pixels by feature id; the increment model is computed once per
  frame and shared by every feature's filter; new ids start a filter, ids unseen for
  `max_missing_frames` frames are dropped. Each feature's filter is independent: what several
  features could tell together about the increment (as `refine` uses it) is not exchanged here.
  (Sharing it naively, feature by feature, is circular: the features' depths came from the same
  earlier increments, and the result is badly overconfident.)

  **Key frames, per feature.** A filter linearises each increment at its current depth. While that
  depth is unknown (the prior is diffuse), an increment that tells little about it (a fine step, a
  feature near the focus of expansion) is linearised at a depth that may be far off, and many such
  increments add up to a confident wrong depth: on a log of 0.05 mm steps the 2-sigma coverage fell
  to 0.1. So each feature keeps a *key* state, and every frame takes one step from its key frame
  straight to the current frame, through the increment between the two motion-log rows and the
  noise of all the increments in between composed (to first order, the dead-reckoning covariance
  propagated along the path). That step gives the feature's estimate at the current frame. It
  becomes the new key once the depth is resolved (1-sigma of log-depth at most
  FusedOptions::key_log_depth_sigma) and the step added a share of information to the key's
  (its log-depth variance at most the key's / (1 + FusedOptions::key_information_gain)). Until the
  depth is resolved the step always starts from the first observation: a two-view estimate over a
  growing baseline, linearised at its own solution. The observations between two keys are not
  used. Where every step resolves the depth and adds to it (coarse steps, points off the focus of
  expansion, the first frames of a track) every frame is a key, as in a plain filter.
  Measured on logs of 1000 frames of 0.05 mm (our simulation, docs/accuracy.md): every `ok` point within
  2 sigma, against a 2-sigma coverage of 0.12 with every frame a key.
*/
#include <Eigen/Core>
#include <map>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/depth_filter.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief Options of FusedEstimator. */
struct FusedOptions {
  /*! The per-feature filter: its settings, and the noise model of every feature (filter.noise: the
      pixel noise weighs each observation, the odometry and yaw noise each increment). */
  DepthFilterOptions filter;
  int max_missing_frames = 30;  //!< drop a feature not observed for this many frames
  /*! A step whose 1-sigma of log-depth is at most this becomes the feature's new key (see the
      file's description); infinity, with key_information_gain 0: a key at every step that does not
      lose information, close to a plain filter. */
  double key_log_depth_sigma = 0.2;
  /*! A resolved feature's step becomes its new key when it added at least this share to the key's
      information on log-depth (0: every step that does not lose information). */
  double key_information_gain = 0.1;
};

/*! \brief Many DepthFilters advanced together frame by frame. */
class FusedEstimator {
public:
  /*!
    \brief An estimator with no feature yet.
    \param camera Camera model (observed pixels are undistorted with it).
    \param rig Yaw rig.
    \param options Filter and noise options.
  */
  FusedEstimator(const CameraModel &camera, const YawRig &rig, const FusedOptions &options = FusedOptions());

  /*! \brief What happened to one observation of the last frame. */
  struct ObservationResult {
    long id = 0; //!< feature id
    DepthFilter::Update update = DepthFilter::Update::Inlier; //!< Inlier also for a (re)start
    bool undistorted = true; //!< false: outside the distortion model, not used
  };

  /*!
    \brief Add the next frame: its motion-log row and its observations (at most one per id).
    The first call starts the filters; later rows must have increasing frame numbers.
  */
  std::vector<ObservationResult> addFrame(const MotionSample &row, const std::vector<FeatureObservation> &observations);

  /*! \brief A feature's estimate at its last observation (PointEstimate::frame; status too_few_frames
      when unknown). */
  PointEstimate estimate(long id) const;
  /*! \brief The feature's filter at its last observation, or nullptr. */
  const DepthFilter *filter(long id) const;
  /*! \brief Forget a feature (its filter and its estimate). */
  void forget(long id);
  /*! \brief Ids currently tracked. */
  std::vector<long> ids() const;
  /*! \brief Distinct key frames held (each carries its composed motion noise; at most one per feature). */
  std::size_t keyFrames() const { return keys_.size(); }
  /*! \brief Frame of the last addFrame(). */
  long frame() const { return last_.frame; }

private:
  struct Feature {
    DepthFilter key;      // the state at the key frame
    DepthFilter current;  // the state at the last observation (a step from the key)
    long key_frame = 0;
    long last_seen = 0;
    int consecutive_outliers = 0;
  };
  // A key frame and the motion from it to the current frame: the composed noise of the increments
  // (translation in the key's vision frame, rotation on the right, IncrementPerturbation's order).
  struct Key {
    MotionSample row;
    Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity(); // the current vision frame's rotation in the key's
    int users = 0;
    long inc_frame = -1;  // frame of the increment below (computed once per frame, on demand)
    IncrementModel inc;
  };
  void setKey(Feature &f, long frame);
  void dropKey(long frame);
  void advanceKeys(const MotionSample &row);
  IncrementPrior keyPrior(const Key &k, const DepthFilter &filter) const;
  CameraModel camera_;
  YawRig rig_;
  FusedOptions o_;
  bool started_ = false;
  MotionSample last_;
  std::map<long, Feature> features_;
  std::map<long, Key> keys_;     // key frame -> its motion to the current frame
};

} // namespace yawdepth
