#pragma once
/*!
  \file stream_estimator.h
  \brief The streaming form of the estimation entry point: frames one by one, as a control loop
  gets them, with `fused` or `window` behind one interface; each feature's estimate at its last
  observed frame, or carried to any later camera pose through the motion.

  The batch entry point for recorded logs is yawdepth::estimatePoints() (yawdepth/pipeline/pipeline.h);
  the servo's yawdepth::DepthProvider and the frame-by-frame benchmarks use this one. It keeps the
  motion-log rows it was given as long as its estimator may report a feature at them (the window's
  length for `window`, max_missing_frames + 1 for `fused`), so that an estimate can be carried from
  the frame it is expressed at to the current pose: \f$ {}^{cur}P = {}^{cur}M_{frame}\, {}^{frame}P \f$
  (yawdepth::curMprev), the covariance rotated with it.
*/
#include <map>
#include <memory>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/estimation/fused_estimator.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/window/window_estimator.h>

namespace yawdepth {

/*! \brief Options of StreamEstimator: the method and that method's options. */
struct StreamOptions {
  Method method = Method::Window; //!< Method::Window (the default) or Method::Fused; the others throw.
  WindowOptions window;           //!< `window`'s options.
  FusedOptions fused;             //!< `fused`'s options.
};

/*! \brief Frames in, one at a time; feature estimates out (see the file). */
class StreamEstimator {
public:
  /*!
    \param camera Camera model (observed pixels are undistorted with it).
    \param rig Camera mount and yaw joint.
    \param options The method and its options; throws yawdepth::Error for a method that does not
           stream (paper, exact, refine) or invalid options.
  */
  StreamEstimator(const CameraModel &camera, const YawRig &rig, const StreamOptions &options = StreamOptions());

  /*!
    \brief Add the next frame: its motion-log row (strictly increasing frame numbers) and its
    observations (at most one per id).
  */
  void addFrame(const MotionSample &row, const std::vector<FeatureObservation> &observations);
  /*! \brief A feature's estimate at its last observed frame (PointEstimate::frame); too_few_frames when unknown. */
  PointEstimate estimate(long id) const;
  /*!
    \brief A feature's estimate carried to the camera at `pose` (a motion-log row, e.g. the current
    odometry, given or not to addFrame()): c_P, c_cov and v_P are at that camera; PointEstimate::frame
    stays the frame the estimate was made at. `too_few_frames` when that frame is no longer kept,
    `behind` when the point is not in front of the camera at `pose`.
  */
  PointEstimate estimateAt(long id, const MotionSample &pose) const;
  /*! \brief Forget a feature (a long-running caller forgets the ids it no longer tracks: bounded memory). */
  void forget(long id);
  /*! \brief The method behind it. */
  Method method() const { return options_.method; }

private:
  YawRig rig_;
  StreamOptions options_;
  std::unique_ptr<FusedEstimator> fused_;
  std::unique_ptr<WindowEstimator> window_;
  std::map<long, MotionSample> rows_; // the rows given, by frame, as long as an estimate may be at them
};

} // namespace yawdepth
