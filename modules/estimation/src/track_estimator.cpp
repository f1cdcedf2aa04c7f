#include <yawdepth/estimation/track_estimator.h>

#include <algorithm>
#include <yawdepth/error.h>

namespace yawdepth {

const char *toString(Method m)
{
  switch (m) {
  case Method::Paper:
    return "paper";
  case Method::Exact:
    return "exact";
  }
  return "unknown";
}

Method methodFromString(const std::string &word)
{
  for (Method m : {Method::Paper, Method::Exact})
    if (word == toString(m))
      return m;
  throw Error("unknown method '" + word + "' (expected paper or exact)");
}

namespace {

long indexOfFrame(const std::vector<MotionSample> &motion, long frame)
{
  const auto it = std::lower_bound(motion.begin(), motion.end(), frame,
                                   [](const MotionSample &s, long f) { return s.frame < f; });
  if (it == motion.end() || it->frame != frame)
    return -1;
  return static_cast<long>(it - motion.begin());
}

} // namespace

PointEstimate estimateTrack(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                            const Track &track, const TrackEstimatorOptions &options)
{
  const auto &obs = track.observations;
  PointEstimate none;
  none.frame = obs.empty() ? 0 : obs.back().frame;
  if (obs.size() < 2) {
    none.status = Status::TooFewFrames;
    return none;
  }
  const Observation &o_prev = obs[obs.size() - 2], &o_cur = obs.back();
  const long i_prev = indexOfFrame(motion, o_prev.frame), i_cur = indexOfFrame(motion, o_cur.frame);
  if (i_prev < 0 || i_cur < 0)
    throw Error("feature " + std::to_string(track.id) + " is observed in frame " +
                std::to_string(i_prev < 0 ? o_prev.frame : o_cur.frame) + ", which the motion log does not have");
  if (i_cur <= i_prev)
    throw Error("feature " + std::to_string(track.id) + ": observations are not in increasing frame order");

  TwoViewOptions tv = options.two_view;
  tv.increments = static_cast<int>(i_cur - i_prev);
  const Eigen::Vector2d uv_prev(o_prev.u, o_prev.v), uv_cur(o_cur.u, o_cur.v);
  switch (options.method) {
  case Method::Paper:
    return estimatePaper(camera, rig, motion[i_prev], motion[i_cur], uv_prev, uv_cur, tv);
  case Method::Exact:
    return estimateExact(camera, rig, motion[i_prev], motion[i_cur], uv_prev, uv_cur, tv);
  }
  throw Error("unknown method");
}

} // namespace yawdepth
