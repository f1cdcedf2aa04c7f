#pragma once
/*!
  \file track_estimator.h
  \brief One entry point for every method: a feature's track and the motion log in, a point out.

  This is the interface the CLI, the servo depth provider and the benchmarks share.
*/
#include <string>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/depth_filter.h>
#include <yawdepth/estimation/two_view.h>
#include <yawdepth/estimation/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief Estimation methods (the `--method` words of `yawdepth estimate`). */
enum class Method {
  Paper, //!< "paper": eq. (5)-(7) on the last increment, as published.
  Exact, //!< "exact": finite-increment two-view form on the last increment, rotation compensated.
  Fused  //!< "fused": recursive inverse-depth filter over every frame (DepthFilter).
};

/*! \brief "paper", "exact", "fused". */
const char *toString(Method m);
/*! \brief Parse a method word; throws yawdepth::Error for an unknown one. */
Method methodFromString(const std::string &word);

/*! \brief Options of estimateTrack(). */
struct TrackEstimatorOptions {
  Method method = Method::Exact; //!< the estimation method
  TwoViewOptions two_view;      //!< paper / exact (its noise and gates are also used by fused)
  DepthFilter::Options filter;  //!< fused: prior, outlier gate, convergence (noise and gates come from two_view)
};

/*!
  \brief Estimate one feature's point at the last frame it was observed in.

  `paper` and `exact` use the last two observations of the track (the last increment the feature
  was seen across; when frames in between are missing, the odometry noise grows with the number
  of motion-log rows spanned). `fused` runs a DepthFilter from the first observation through every
  motion-log row to the last observation (predicting through rows where the feature is missing).
  \param camera Camera model (observed pixels are undistorted with it).
  \param rig Yaw rig.
  \param motion Motion-log rows sorted by strictly increasing frame; every observed frame must be in
         it (throws yawdepth::Error otherwise).
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

} // namespace yawdepth
