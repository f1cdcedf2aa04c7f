#include <yawdepth/estimation/track_estimator.h>

#include <algorithm>
#include <limits>
#include <map>
#include <yawdepth/error.h>
#include <yawdepth/estimation/fused_estimator.h>

namespace yawdepth {

namespace {

/* paper and exact's options: the call's noise model and gates, over `increments` motion-log rows. */
TwoViewOptions twoViewOptions(const TrackEstimatorOptions &options, long increments)
{
  TwoViewOptions tv;
  tv.noise = options.noise;
  tv.gates = options.gates;
  tv.compute_covariance = options.compute_covariance;
  tv.increments = static_cast<int>(increments);
  return tv;
}

void checkObservedFrames(const std::vector<MotionSample> &motion, const Track &track)
{
  long last = std::numeric_limits<long>::min();
  for (const Observation &o : track.observations) {
    if (rowOfFrame(motion, o.frame) < 0)
      throw Error("feature " + std::to_string(track.id) + " is observed in frame " + std::to_string(o.frame) +
                  ", which the motion log does not have");
    if (o.frame <= last)
      throw Error("feature " + std::to_string(track.id) + ": observations are not in increasing frame order");
    last = o.frame;
  }
}

/* The log-depth state is positive by construction; image motion that only a point behind the
   camera explains is caught by the exact two-view form on the widest pair of observations. Only
   when the filter itself did not resolve the depth well: near the focus of expansion that sign
   flips with noise, and a confident filter has seen consistent positive depth. */
PointEstimate checkBehind(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                          const Track &track, const DepthFilter &filter, const TrackEstimatorOptions &options,
                          const PointEstimate &e)
{
  if (!(e.ok() || e.status == Status::Degenerate) || !filter.initialized() || filter.inliers() < 2 ||
      !(filter.logDepthSigma() > 0.3))
    return e;
  const auto &obs = track.observations;
  const long first_row = rowOfFrame(motion, obs.front().frame), last_row = rowOfFrame(motion, obs.back().frame);
  TwoViewOptions tv = twoViewOptions(options, last_row - first_row);
  tv.compute_covariance = false;
  const PointEstimate wide =
      estimateExact(camera, rig, motion[first_row], motion[last_row], Eigen::Vector2d(obs.front().u, obs.front().v),
                    Eigen::Vector2d(obs.back().u, obs.back().v), tv);
  if (wide.status != Status::Behind)
    return e;
  PointEstimate behind;
  behind.status = Status::Behind;
  behind.frame = e.frame;
  behind.parallax_px = e.parallax_px;
  return behind;
}

} // namespace

std::vector<PointEstimate> estimateTracks(const CameraModel &camera, const YawRig &rig,
                                          const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                          const TrackEstimatorOptions &options,
                                          std::vector<std::vector<bool>> *outliers)
{
  std::vector<PointEstimate> out;
  out.reserve(tracks.size());
  if (outliers)
    outliers->assign(tracks.size(), {});
  if (options.method == TrackMethod::Fused) {
    // Frame by frame, all features together (FusedEstimator), each track's estimate taken at its
    // last observation.
    out.assign(tracks.size(), PointEstimate());
    if (outliers)
      for (std::size_t i = 0; i < tracks.size(); ++i)
        (*outliers)[i].assign(tracks[i].observations.size(), false);
    std::map<long, std::vector<std::pair<std::size_t, std::size_t>>> by_frame; // frame -> (track, obs)
    std::map<long, std::vector<std::size_t>> ending;                          // frame -> tracks ending there
    long first = std::numeric_limits<long>::max(), last = std::numeric_limits<long>::min();
    for (std::size_t i = 0; i < tracks.size(); ++i) {
      checkObservedFrames(motion, tracks[i]);
      const auto &obs = tracks[i].observations;
      out[i].frame = obs.empty() ? 0 : obs.back().frame;
      out[i].status = Status::TooFewFrames;
      if (obs.size() < 2)
        continue;
      for (std::size_t k = 0; k < obs.size(); ++k)
        by_frame[obs[k].frame].emplace_back(i, k);
      ending[obs.back().frame].push_back(i);
      first = std::min(first, obs.front().frame);
      last = std::max(last, obs.back().frame);
    }
    if (by_frame.empty())
      return out;
    FusedOptions fo;
    static_cast<DepthFilterSettings &>(fo.filter) = options.filter;
    fo.filter.noise = options.noise;
    fo.filter.gates = options.gates;
    fo.max_missing_frames = std::numeric_limits<int>::max() / 2; // tracks are dropped at their last frame
    FusedEstimator fused(camera, rig, fo);
    for (long r = rowOfFrame(motion, first); r <= rowOfFrame(motion, last); ++r) {
      const MotionSample &row = motion[static_cast<std::size_t>(r)];
      std::vector<FeatureObservation> fobs;
      const auto bf = by_frame.find(row.frame);
      if (bf != by_frame.end())
        for (const auto &[ti, k] : bf->second)
          fobs.push_back({tracks[ti].id, tracks[ti].observations[k].u, tracks[ti].observations[k].v});
      const auto results = fused.addFrame(row, fobs);
      if (outliers && bf != by_frame.end())
        for (std::size_t j = 0; j < results.size(); ++j)
          if (results[j].update == DepthFilter::Update::Outlier)
            (*outliers)[bf->second[j].first][bf->second[j].second] = true;
      const auto en = ending.find(row.frame);
      if (en == ending.end())
        continue;
      for (std::size_t ti : en->second) {
        const DepthFilter *f = fused.filter(tracks[ti].id);
        if (f) {
          out[ti] = checkBehind(camera, rig, motion, tracks[ti], *f, options, f->estimate(rig));
        } else {
          out[ti].status = Status::UndistortFailed;
        }
        out[ti].frame = row.frame;
        fused.forget(tracks[ti].id);
      }
    }
  } else {
    for (std::size_t i = 0; i < tracks.size(); ++i) {
      out.push_back(estimateTrack(camera, rig, motion, tracks[i], options));
      if (outliers)
        (*outliers)[i].assign(tracks[i].observations.size(), false);
    }
  }
  return out;
}

PointEstimate estimateTrack(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                            const Track &track, const TrackEstimatorOptions &options)
{
  if (options.method == TrackMethod::Fused) // one implementation: the frame-by-frame FusedEstimator
    return estimateTracks(camera, rig, motion, std::vector<Track>{track}, options).front();
  const auto &obs = track.observations;
  PointEstimate none;
  none.frame = obs.empty() ? 0 : obs.back().frame;
  if (obs.size() < 2) {
    none.status = Status::TooFewFrames;
    return none;
  }
  const Observation &o_prev = obs[obs.size() - 2], &o_cur = obs.back();
  const long i_prev = rowOfFrame(motion, o_prev.frame), i_cur = rowOfFrame(motion, o_cur.frame);
  if (i_prev < 0 || i_cur < 0)
    throw Error("feature " + std::to_string(track.id) + " is observed in frame " +
                std::to_string(i_prev < 0 ? o_prev.frame : o_cur.frame) + ", which the motion log does not have");
  if (i_cur <= i_prev)
    throw Error("feature " + std::to_string(track.id) + ": observations are not in increasing frame order");

  const TwoViewOptions tv = twoViewOptions(options, i_cur - i_prev);
  const Eigen::Vector2d uv_prev(o_prev.u, o_prev.v), uv_cur(o_cur.u, o_cur.v);
  switch (options.method) {
  case TrackMethod::Paper:
    return estimatePaper(camera, rig, motion[i_prev], motion[i_cur], uv_prev, uv_cur, tv);
  case TrackMethod::Exact:
    return estimateExact(camera, rig, motion[i_prev], motion[i_cur], uv_prev, uv_cur, tv);
  case TrackMethod::Fused:
    break;
  }
  throw Error("unknown method");
}

} // namespace yawdepth
