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

/* The log-depth state is positive by construction; image motion that only a point behind the
   camera explains is caught by the exact two-view form on the widest pair of observations. Only
   when the filter itself did not resolve the depth well: near the focus of expansion that sign
   flips with noise, and a confident filter has seen consistent positive depth. */
PointEstimate checkBehind(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input, std::size_t t,
                          const DepthFilter &filter, const TrackEstimatorOptions &options, const PointEstimate &e)
{
  if (!(e.ok() || e.status == Status::Degenerate) || !filter.initialized() || filter.inliers() < 2 ||
      !(filter.logDepthSigma() > 0.3))
    return e;
  const auto &obs = input.tracks()[t].observations;
  const std::size_t first_row = input.row(t, 0), last_row = input.row(t, obs.size() - 1);
  TwoViewOptions tv = twoViewOptions(options, static_cast<long>(last_row - first_row));
  tv.compute_covariance = false;
  const PointEstimate wide = estimateExact(camera, rig, input.motion()[first_row], input.motion()[last_row],
                                           Eigen::Vector2d(obs.front().u, obs.front().v),
                                           Eigen::Vector2d(obs.back().u, obs.back().v), tv);
  if (wide.status != Status::Behind)
    return e;
  PointEstimate behind;
  behind.status = Status::Behind;
  behind.frame = e.frame;
  behind.parallax_px = e.parallax_px;
  return behind;
}

/* paper or exact on the track's last two observations (the last increment the feature was seen
   across; the odometry noise grows with the motion-log rows spanned). */
PointEstimate estimateOnLastPair(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                 std::size_t t, const TrackEstimatorOptions &options)
{
  const auto &obs = input.tracks()[t].observations;
  PointEstimate none;
  none.frame = obs.empty() ? 0 : obs.back().frame;
  if (obs.size() < 2) {
    none.status = Status::TooFewFrames;
    return none;
  }
  const std::size_t n = obs.size();
  const std::size_t i_prev = input.row(t, n - 2), i_cur = input.row(t, n - 1);
  const TwoViewOptions tv = twoViewOptions(options, static_cast<long>(i_cur - i_prev));
  const Eigen::Vector2d uv_prev(obs[n - 2].u, obs[n - 2].v), uv_cur(obs[n - 1].u, obs[n - 1].v);
  const MotionSample &prev = input.motion()[i_prev], &cur = input.motion()[i_cur];
  return options.method == TrackMethod::Paper ? estimatePaper(camera, rig, prev, cur, uv_prev, uv_cur, tv)
                                              : estimateExact(camera, rig, prev, cur, uv_prev, uv_cur, tv);
}

} // namespace

std::vector<PointEstimate> estimateTracks(const CameraModel &camera, const YawRig &rig,
                                          const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                          const TrackEstimatorOptions &options,
                                          std::vector<std::vector<bool>> *outliers)
{
  return estimateTracks(camera, rig, validateInputs(motion, tracks), options, outliers);
}

std::vector<PointEstimate> estimateTracks(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                          const TrackEstimatorOptions &options,
                                          std::vector<std::vector<bool>> *outliers)
{
  const std::vector<MotionSample> &motion = input.motion();
  const std::vector<Track> &tracks = input.tracks();
  std::vector<PointEstimate> out;
  out.reserve(tracks.size());
  if (outliers) {
    outliers->assign(tracks.size(), {});
    for (std::size_t i = 0; i < tracks.size(); ++i)
      (*outliers)[i].assign(tracks[i].observations.size(), false);
  }
  if (options.method != TrackMethod::Fused) {
    for (std::size_t i = 0; i < tracks.size(); ++i)
      out.push_back(estimateOnLastPair(camera, rig, input, i, options));
    return out;
  }
  // Frame by frame, all features together (FusedEstimator), each track's estimate taken at its last
  // observation.
  out.assign(tracks.size(), PointEstimate());
  std::map<std::size_t, std::vector<std::size_t>> ending; // row -> tracks ending there
  std::size_t first = std::numeric_limits<std::size_t>::max(), last = 0;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const auto &obs = tracks[i].observations;
    out[i].frame = obs.empty() ? 0 : obs.back().frame;
    out[i].status = Status::TooFewFrames;
    if (obs.size() < 2)
      continue;
    ending[input.row(i, obs.size() - 1)].push_back(i);
    first = std::min(first, input.row(i, 0));
    last = std::max(last, input.row(i, obs.size() - 1));
  }
  if (ending.empty())
    return out;
  FusedOptions fo;
  static_cast<DepthFilterSettings &>(fo.filter) = options.filter;
  fo.filter.noise = options.noise;
  fo.filter.gates = options.gates;
  fo.max_missing_frames = std::numeric_limits<int>::max() / 2; // tracks are dropped at their last frame
  FusedEstimator fused(camera, rig, fo);
  for (std::size_t r = first; r <= last; ++r) {
    const MotionSample &row = motion[r];
    std::vector<FeatureObservation> fobs;
    std::vector<TracksByFrame::Entry> used; // the observations given, in fobs' order
    for (const TracksByFrame::Entry &e : input.observedAt(r))
      if (tracks[e.first].observations.size() >= 2) {
        const Observation &ob = tracks[e.first].observations[e.second];
        fobs.push_back({tracks[e.first].id, ob.u, ob.v});
        used.push_back(e);
      }
    const auto results = fused.addFrame(row, fobs);
    if (outliers)
      for (std::size_t j = 0; j < results.size(); ++j)
        if (results[j].update == DepthFilter::Update::Outlier)
          (*outliers)[used[j].first][used[j].second] = true;
    const auto en = ending.find(r);
    if (en == ending.end())
      continue;
    for (std::size_t ti : en->second) {
      const DepthFilter *f = fused.filter(tracks[ti].id);
      if (f) {
        out[ti] = checkBehind(camera, rig, input, ti, *f, options, f->estimate(rig));
      } else {
        out[ti].status = Status::UndistortFailed;
      }
      out[ti].frame = row.frame;
      fused.forget(tracks[ti].id);
    }
  }
  return out;
}

PointEstimate estimateTrack(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                            const Track &track, const TrackEstimatorOptions &options)
{
  const std::vector<Track> one{track};
  return estimateTracks(camera, rig, validateInputs(motion, one), options).front();
}

} // namespace yawdepth
