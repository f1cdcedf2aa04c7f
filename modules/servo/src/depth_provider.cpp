#include <yawdepth/servo/depth_provider.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

bool finitePositive(double v) { return std::isfinite(v) && v > 0; }

StreamOptions streamOptions(const DepthProviderOptions &o)
{
  o.validate();
  StreamOptions s;
  s.method = o.method;
  s.noise = o.noise;
  s.window = o.window;
  s.prior_depth = o.initial_depth > 0 ? o.initial_depth : o.prior_depth;
  s.max_missing_frames = o.max_missing_frames;
  return s;
}

} // namespace

void DepthProviderOptions::validate() const
{
  if (!finitePositive(prior_depth))
    throw Error("depth provider: prior_depth must be finite and positive");
  if (!std::isfinite(prior_relative_sigma) || prior_relative_sigma < 0)
    throw Error("depth provider: prior_relative_sigma must be finite and non-negative");
  if (!finitePositive(converged_relative_sigma))
    throw Error("depth provider: converged_relative_sigma must be finite and positive");
  if (!std::isfinite(release_factor) || release_factor < 1)
    throw Error("depth provider: release_factor must be at least 1");
  if (!(std::isfinite(revoke_sigmas) && revoke_sigmas > 0))
    throw Error("depth provider: revoke_sigmas must be finite and positive");
  if (confirm_periods < 1)
    throw Error("depth provider: confirm_periods must be at least 1");
  if (!finitePositive(min_depth) || !finitePositive(max_depth) || !(max_depth > min_depth))
    throw Error("depth provider: need 0 < min_depth < max_depth");
  if (!std::isfinite(min_translation) || min_translation < 0)
    throw Error("depth provider: min_translation must be finite and non-negative");
  if (max_skipped_periods < 1)
    throw Error("depth provider: max_skipped_periods must be positive");
  if (!std::isfinite(initial_depth) || initial_depth < 0)
    throw Error("depth provider: initial_depth must be finite and non-negative");
  if (max_missing_frames < 0)
    throw Error("depth provider: max_missing_frames must be non-negative");
  if (window < 2)
    throw Error("depth provider: window must be at least 2 frames");
  noise.validate();
}

DepthProvider::DepthProvider(const CameraModel &camera, const YawRig &rig, const Options &options)
    : camera_(camera), rig_(rig), o_(options), stream_(camera, rig, streamOptions(options))
{
}

DepthProvider::DepthProvider(const vpCameraParameters &camera, const YawRig &rig, const Options &options)
    : DepthProvider(CameraModel(camera), rig, options)
{
}

double DepthProvider::priorOf(long id) const
{
  const auto it = priors_.find(id);
  const double Z = it == priors_.end() ? o_.prior_depth : it->second;
  return std::clamp(Z, o_.min_depth, o_.max_depth);
}

void DepthProvider::setPrior(long id, double Z)
{
  if (!finitePositive(Z))
    throw Error("depth provider: a prior depth must be finite and positive");
  priors_[id] = Z;
  refresh(id);
}

PointEstimate DepthProvider::estimate(long id) const
{
  // The estimate carried from its frame (the feature's last observed frame) to the current period,
  // through the odometry.
  return have_fed_ ? stream_.estimateAt(id, current_) : stream_.estimate(id);
}

void DepthProvider::refresh(long id)
{
  FeatureDepth &f = state_[id];
  const bool was_converged = f.converged;
  f.id = id;
  const PointEstimate e = estimate(id);
  f.status = e.status;
  f.estimate = std::numeric_limits<double>::quiet_NaN();
  f.estimate_sigma = std::numeric_limits<double>::quiet_NaN();
  bool use = false;
  Consistency &c = consistency_[id];
  if (e.ok() && std::isfinite(e.c_P.z()) && e.c_P.z() > 0 && std::isfinite(e.sigmaZ())) {
    f.estimate = e.c_P.z();
    f.estimate_sigma = e.sigmaZ();
    const double rel = f.estimate_sigma / f.estimate;
    const double threshold = o_.converged_relative_sigma * (was_converged ? o_.release_factor : 1.0);
    // The jump test: the last period's point, carried to this camera frame by the odometry.
    const vpHomogeneousMatrix oMc = wMc(rig_, current_);
    bool jumped = false;
    if (c.has_prev) {
      const vpColVector c_prev = oMc.inverse() * vpColVector({c.o_P_prev.x(), c.o_P_prev.y(), c.o_P_prev.z(), 1.0});
      const double allowed = o_.revoke_sigmas * std::hypot(c.sigma_prev, f.estimate_sigma);
      jumped = std::abs(f.estimate - c_prev[2]) > allowed;
    }
    const vpColVector o_P = oMc * vpColVector({e.c_P.x(), e.c_P.y(), e.c_P.z(), 1.0});
    c.o_P_prev = Eigen::Vector3d(o_P[0], o_P[1], o_P[2]);
    c.sigma_prev = f.estimate_sigma;
    c.has_prev = true;
    if (jumped) {
      if (was_converged)
        ++f.revocations;
      c.wait = was_converged || c.wait > 0 ? o_.confirm_periods : 0;
    } else if (c.wait > 0 && rel < threshold) {
      --c.wait;
    }
    use = rel < threshold && !jumped && c.wait == 0;
  } else {
    c.has_prev = false;
  }
  f.converged = use;
  if (use) {
    f.depth = std::clamp(f.estimate, o_.min_depth, o_.max_depth);
    f.sigma = f.estimate_sigma;
  } else {
    f.depth = priorOf(id);
    f.sigma = f.depth * o_.prior_relative_sigma;
  }
}

void DepthProvider::update(const MotionSample &odometry, const std::vector<std::pair<long, vpImagePoint>> &points)
{
  if (!std::isfinite(odometry.x) || !std::isfinite(odometry.y) || !std::isfinite(odometry.z) ||
      !std::isfinite(odometry.heading) || !std::isfinite(odometry.yaw) || !odometry.theta_u.allFinite())
    throw Error("depth provider: odometry must be finite");
  std::set<long> seen;
  for (const auto &p : points)
    if (!seen.insert(p.first).second)
      throw Error("depth provider: feature id " + std::to_string(p.first) + " given twice in one period");
  ++period_;
  current_ = odometry;

  // Feed the estimator only when the camera moved enough since the last frame it got.
  bool feed = !have_fed_;
  if (have_fed_) {
    const vpHomogeneousMatrix M = curMprev(rig_, last_fed_, odometry);
    const double moved = std::sqrt(M[0][3] * M[0][3] + M[1][3] * M[1][3] + M[2][3] * M[2][3]);
    feed = moved >= o_.min_translation || skipped_ + 1 >= o_.max_skipped_periods;
  }
  if (feed) {
    MotionSample row = odometry;
    row.frame = ++frames_used_;
    std::vector<FeatureObservation> obs;
    obs.reserve(points.size());
    for (const auto &p : points)
      obs.push_back(FeatureObservation{p.first, p.second.get_u(), p.second.get_v()});
    stream_.addFrame(row, obs);
    last_fed_ = odometry;
    have_fed_ = true;
    skipped_ = 0;
  } else {
    ++skipped_;
  }
  for (const auto &p : points)
    refresh(p.first);
  for (const auto &p : points)
    last_seen_[p.first] = frames_used_;
  // Features no longer tracked by the estimator fall back to their prior; the window estimator
  // forgets those unseen for max_missing_frames estimator frames, so that a loop that runs for
  // hours keeps bounded memory.
  for (auto it = last_seen_.begin(); it != last_seen_.end();) {
    if (frames_used_ - it->second > o_.max_missing_frames) {
      stream_.forget(it->first);
      consistency_.erase(it->first);
      state_.erase(it->first); // forgotten: depth(id) is the prior again, and memory stays bounded
      it = last_seen_.erase(it);
    } else {
      ++it;
    }
  }
  for (auto &kv : state_)
    if (!seen.count(kv.first))
      refresh(kv.first);
}

void DepthProvider::update(const vpHomogeneousMatrix &wMv, const std::vector<std::pair<long, vpImagePoint>> &points,
                           double yaw)
{
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 4; ++j)
      if (!std::isfinite(wMv[i][j]))
        throw Error("depth provider: the pose must be finite");
  if (!wMv.isAnHomogeneousMatrix(1e-6))
    throw Error("depth provider: the pose's rotation is not a rotation matrix");
  update(MotionSample::fromPose(0, wMv, yaw), points);
}

FeatureDepth DepthProvider::info(long id) const
{
  const auto it = state_.find(id);
  if (it != state_.end())
    return it->second;
  FeatureDepth f;
  f.id = id;
  f.depth = priorOf(id);
  f.sigma = f.depth * o_.prior_relative_sigma;
  return f;
}

double DepthProvider::depth(long id) const { return info(id).depth; }
double DepthProvider::sigma(long id) const { return info(id).sigma; }
Status DepthProvider::status(long id) const { return info(id).status; }
bool DepthProvider::converged(long id) const { return info(id).converged; }

void DepthProvider::apply(long id, vpFeaturePoint &s) const { s.set_Z(depth(id)); }

void DepthProvider::apply(const std::vector<long> &ids, std::vector<vpFeaturePoint> &features) const
{
  if (ids.size() != features.size())
    throw Error("depth provider: apply() needs one id per feature");
  for (std::size_t i = 0; i < ids.size(); ++i)
    apply(ids[i], features[i]);
}

void DepthProvider::buildFrom(long id, const vpImagePoint &observed, vpFeaturePoint &s) const
{
  double x = 0, y = 0;
  camera_.pixelToMeter(observed, x, y);
  s.buildFrom(x, y, depth(id));
}

} // namespace yawdepth
