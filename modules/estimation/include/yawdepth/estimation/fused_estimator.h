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
*/
#include <map>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/depth_filter.h>
#include <yawdepth/estimation/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief Options of FusedEstimator. */
struct FusedOptions {
  DepthFilterOptions filter;    //!< per-feature filter (its noise model is the pixel/odometry/yaw model)
  double sigma_px = 0.3;        //!< pixel noise of the observations (px)
  int max_missing_frames = 30;  //!< drop a feature not observed for this many frames
};

/*! \brief One observation of a frame: feature id and observed (distorted) pixel. */
struct FrameObservation {
  long id = 0;         //!< feature id
  /*! observed pixel: column (px) */
  double u = 0, v = 0; //!< observed pixel: row (px)
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
  std::vector<ObservationResult> addFrame(const MotionSample &row, const std::vector<FrameObservation> &observations);

  /*! \brief Current estimate of a feature (status too_few_frames when unknown). */
  PointEstimate estimate(long id) const;
  /*! \brief The feature's filter, or nullptr. */
  const DepthFilter *filter(long id) const;
  /*! \brief Forget a feature. */
  void remove(long id) { features_.erase(id); }
  /*! \brief Ids currently tracked. */
  std::vector<long> ids() const;
  /*! \brief Frame of the last addFrame(). */
  long frame() const { return last_.frame; }

private:
  struct Feature {
    DepthFilter filter;
    long last_seen = 0;
  };
  CameraModel camera_;
  YawRig rig_;
  FusedOptions o_;
  bool started_ = false;
  MotionSample last_;
  std::map<long, Feature> features_;
};

} // namespace yawdepth
