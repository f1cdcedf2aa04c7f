#pragma once
/*!
  \file track_estimator.h
  \brief The per-feature methods (paper, exact, fused) on whole tracks: a feature's track and the
  motion log in, a point out.

  The entry point for every method, window and refine included, with the outlier flags and the
  motion as estimated, is yawdepth::estimatePoints() (yawdepth/pipeline/pipeline.h), which the
  command line and the benchmarks use.
*/
#include <string>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/depth_filter.h>
#include <yawdepth/estimation/two_view.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/geometry/track_inputs.h>

namespace yawdepth {

/*! \brief Options of estimateTrack(): the method, the call's one noise model and gates, and each
    method's settings. */
struct TrackEstimatorOptions {
  TrackMethod method = TrackMethod::Exact; //!< paper, exact or fused (window and refine: yawdepth::estimatePoints).
  NoiseModel noise;                        //!< Noise of pixels, motion and yaw readings (every method).
  GateOptions gates;                       //!< no_motion / degenerate gates (every method).
  bool compute_covariance = true;          //!< paper, exact: false skips the covariance (c_cov NaN); fused always has it.
  DepthFilterSettings filter;              //!< fused: the filter's prior, outlier gate and convergence.
};

/*!
  \brief Estimate one feature's point at the last frame it was observed in.

  `paper` and `exact` use the last two observations of the track (the last increment the feature
  was seen across; when frames in between are missing, the odometry noise grows with the number
  of motion-log rows spanned). `fused` runs a DepthFilter from the first observation through every
  motion-log row to the last observation (predicting through rows where the feature is missing).
  \param camera Camera model (observed pixels are undistorted with it).
  \param rig Yaw rig.
  \param motion Motion-log rows; the track and the log must obey yawdepth::validateInputs()'s rules
         (throws yawdepth::Error otherwise).
  \param track The feature's observations.
  \param options Method and its options.
  \return An estimate whose status says whether it is valid; `too_few_frames` for fewer than two
          observations.
*/
PointEstimate estimateTrack(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                            const Track &track, const TrackEstimatorOptions &options = TrackEstimatorOptions());

/*!
  \brief Estimate every track (same order). Same as estimateTrack() on each, but computes each
  motion increment once for all tracks.
  \param camera, rig, options As for estimateTrack().
  \param motion Motion-log rows, as for estimateTrack().
  \param tracks The features.
  \param outliers If not null, receives per track and per observation whether `fused` rejected it
         as an outlier (all false for the other methods).
*/
std::vector<PointEstimate> estimateTracks(const CameraModel &camera, const YawRig &rig,
                                          const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                          const TrackEstimatorOptions &options = TrackEstimatorOptions(),
                                          std::vector<std::vector<bool>> *outliers = nullptr);

/*!
  \brief estimateTracks() on input already validated (yawdepth::validateInputs(): what
  yawdepth::estimatePoints() passes); the same results.
*/
std::vector<PointEstimate> estimateTracks(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                          const TrackEstimatorOptions &options = TrackEstimatorOptions(),
                                          std::vector<std::vector<bool>> *outliers = nullptr);

} // namespace yawdepth
