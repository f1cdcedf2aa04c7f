#include <yawdepth/estimation/fused_estimator.h>

#include <string>
#include <yawdepth/error.h>

namespace yawdepth {

FusedEstimator::FusedEstimator(const CameraModel &camera, const YawRig &rig, const FusedOptions &options)
    : camera_(camera), rig_(rig), o_(options)
{
  if (!std::isfinite(o_.sigma_px) || o_.sigma_px < 0)
    throw Error("fused: sigma_px must be finite and non-negative");
  if (o_.max_missing_frames < 0)
    throw Error("fused: max_missing_frames must be non-negative");
  DepthFilter check(o_.filter, camera.kx(), camera.ky()); // validates the filter options
}

std::vector<long> FusedEstimator::ids() const
{
  std::vector<long> out;
  for (const auto &kv : features_)
    out.push_back(kv.first);
  return out;
}

const DepthFilter *FusedEstimator::filter(long id) const
{
  const auto it = features_.find(id);
  return it == features_.end() ? nullptr : &it->second.filter;
}

PointEstimate FusedEstimator::estimate(long id) const
{
  const auto it = features_.find(id);
  if (it == features_.end()) {
    PointEstimate e;
    e.status = Status::TooFewFrames;
    e.frame = last_.frame;
    return e;
  }
  return it->second.filter.estimate(rig_);
}

std::vector<FusedEstimator::ObservationResult> FusedEstimator::addFrame(const MotionSample &row,
                                                                        const std::vector<FrameObservation> &observations)
{
  if (started_ && row.frame <= last_.frame)
    throw Error("fused: frame " + std::to_string(row.frame) + " does not follow frame " + std::to_string(last_.frame));
  // Undistort the observations once.
  struct Obs {
    long id;
    Eigen::Vector2d m;
    Eigen::Matrix2d cov;
    bool ok;
  };
  std::vector<Obs> obs;
  obs.reserve(observations.size());
  const double s2 = o_.sigma_px * o_.sigma_px;
  for (const FrameObservation &fo : observations) {
    Obs o{fo.id, Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity(), false};
    Eigen::Matrix2d J;
    if (std::isfinite(fo.u) && std::isfinite(fo.v) && camera_.undistort(Eigen::Vector2d(fo.u, fo.v), o.m, &J)) {
      o.cov = s2 * J * J.transpose() + 1e-24 * Eigen::Matrix2d::Identity();
      o.ok = true;
    }
    obs.push_back(o);
  }
  std::vector<ObservationResult> results(obs.size());
  for (std::size_t i = 0; i < obs.size(); ++i) {
    results[i].id = obs[i].id;
    results[i].undistorted = obs[i].ok;
  }

  auto start = [&](const Obs &o) {
    Feature f{DepthFilter(o_.filter, camera_.kx(), camera_.ky()), row.frame};
    f.filter.initialize(row.frame, row.yaw, o.m, o.cov);
    features_[o.id] = std::move(f);
  };

  if (!started_) {
    started_ = true;
    last_ = row;
    for (const Obs &o : obs)
      if (o.ok)
        start(o);
    return results;
  }

  // The increment is computed once and shared by every feature's filter.
  const IncrementModel inc = IncrementModel::between(rig_, last_, row);
  std::map<long, std::size_t> observed;
  for (std::size_t i = 0; i < obs.size(); ++i)
    if (obs[i].ok)
      observed[obs[i].id] = i;
  for (auto it = features_.begin(); it != features_.end();) {
    Feature &f = it->second;
    const auto o = observed.find(it->first);
    if (o != observed.end()) {
      const std::size_t i = o->second;
      results[i].update = f.filter.step(inc, &obs[i].m, &obs[i].cov);
      f.last_seen = row.frame;
    } else {
      f.filter.step(inc);
    }
    if (!f.filter.initialized() || row.frame - f.last_seen > o_.max_missing_frames)
      it = features_.erase(it);
    else
      ++it;
  }
  // New features.
  for (const Obs &o : obs)
    if (o.ok && features_.find(o.id) == features_.end())
      start(o);
  last_ = row;
  return results;
}

} // namespace yawdepth
