#include <yawdepth/estimation/fused_estimator.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

/* An observation undistorted once: its normalised point and covariance, ok false when the pixel is
   outside the distortion model. */
struct UndistortedObservation {
  long id;
  Eigen::Vector2d m;
  Eigen::Matrix2d cov;
  bool ok;
};

std::vector<UndistortedObservation> undistortObservations(const CameraModel &camera, double sigma_px,
                                                          const std::vector<FeatureObservation> &observations)
{
  std::vector<UndistortedObservation> obs;
  obs.reserve(observations.size());
  const double s2 = sigma_px * sigma_px;
  for (const FeatureObservation &fo : observations) {
    UndistortedObservation o{fo.id, Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity(), false};
    Eigen::Matrix2d J;
    if (std::isfinite(fo.u) && std::isfinite(fo.v) && camera.undistort(Eigen::Vector2d(fo.u, fo.v), o.m, &J)) {
      o.cov = s2 * J * J.transpose() + 1e-24 * Eigen::Matrix2d::Identity();
      o.ok = true;
    }
    obs.push_back(o);
  }
  return obs;
}

/* One result per observation, before any update: its id and whether it was undistorted. */
std::vector<FusedEstimator::ObservationResult> initialResults(const std::vector<UndistortedObservation> &obs)
{
  std::vector<FusedEstimator::ObservationResult> results(obs.size());
  for (std::size_t i = 0; i < obs.size(); ++i) {
    results[i].id = obs[i].id;
    results[i].undistorted = obs[i].ok;
  }
  return results;
}

/* The index in obs of every id observed and undistorted. */
std::map<long, std::size_t> usableObservations(const std::vector<UndistortedObservation> &obs)
{
  std::map<long, std::size_t> observed;
  for (std::size_t i = 0; i < obs.size(); ++i)
    if (obs[i].ok)
      observed[obs[i].id] = i;
  return observed;
}

enum class KeyChange { None, Restart, NewKey };

/* What a feature's key becomes after a step of its filter (counting the outliers in a row):
   restarted after too many outliers, a new key when the filter restarted itself, or once the depth
   is resolved and the step added enough information to it. */
KeyChange keyChangeAfter(DepthFilter::Update u, int &consecutive_outliers, const DepthFilter &current,
                         const DepthFilter &key, const FusedOptions &o)
{
  if (u == DepthFilter::Update::Outlier)
    return ++consecutive_outliers >= o.filter.max_consecutive_outliers ? KeyChange::Restart : KeyChange::None;
  consecutive_outliers = 0;
  if (u == DepthFilter::Update::Restarted)
    return KeyChange::NewKey;
  const double sc = current.logDepthSigma(), sk = key.logDepthSigma();
  if (sc <= o.key_log_depth_sigma && (key.inliers() < 2 || sc * sc * (1.0 + o.key_information_gain) <= sk * sk))
    return KeyChange::NewKey;
  return KeyChange::None;
}

} // namespace

FusedEstimator::FusedEstimator(const CameraModel &camera, const YawRig &rig, const FusedOptions &options)
    : camera_(camera), rig_(rig), o_(options)
{
  o_.filter.noise.validate();
  if (o_.max_missing_frames < 0)
    throw Error("fused: max_missing_frames must be non-negative");
  if (!(o_.key_log_depth_sigma > 0))
    throw Error("fused: key_log_depth_sigma must be positive");
  if (!(o_.key_information_gain >= 0) || !std::isfinite(o_.key_information_gain))
    throw Error("fused: key_information_gain must be finite and non-negative");
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
  return it == features_.end() ? nullptr : &it->second.current;
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
  return it->second.current.estimate(rig_);
}

void FusedEstimator::forget(long id)
{
  const auto it = features_.find(id);
  if (it == features_.end())
    return;
  dropKey(it->second.key_frame);
  features_.erase(it);
}

void FusedEstimator::setKey(Feature &f, long frame)
{
  dropKey(f.key_frame);
  f.key = f.current;
  f.key_frame = frame;
  Key &k = keys_[frame];
  if (k.users++ == 0) {
    k = Key();
    k.users = 1;
    k.row = last_;
  }
}

void FusedEstimator::dropKey(long frame)
{
  const auto it = keys_.find(frame);
  if (it != keys_.end() && --it->second.users <= 0)
    keys_.erase(it);
}

/* Carry every key's composed motion noise over the increment last_ -> row (composeIncrementNoise). */
void FusedEstimator::advanceKeys(const MotionSample &row)
{
  if (o_.filter.noise.motion_noise == MotionNoise::Absolute || keys_.empty())
    return; // pose errors do not accumulate: the prior of any increment is that of two poses
  const Eigen::Matrix3d Rp = last_.rotation();
  const Eigen::Vector3d d = Rp.transpose() * (row.position() - last_.position());
  const Eigen::Matrix3d dR = Rp.transpose() * row.rotation();
  const bool six_dof = last_.six_dof || row.six_dof;
  const double st = incrementTranslationSigma(o_.filter.noise, d.norm());
  const Eigen::Vector3d sr = incrementRotationSigma(o_.filter.noise, six_dof, d.norm(), Eigen::AngleAxisd(dR).angle());
  Eigen::Matrix<double, 6, 1> q;
  q << st * st, st * st, st * st, sr.cwiseAbs2();
  const Eigen::Matrix<double, 6, 6> Q = q.asDiagonal();
  for (auto &kv : keys_)
    composeIncrementNoise(kv.second.cov, kv.second.R, d, dR, Q);
}

IncrementPrior FusedEstimator::keyPrior(const Key &k, const DepthFilter &filter) const
{
  IncrementPrior p = filter.defaultPrior(k.inc.six_dof, k.inc.distance, k.inc.angle);
  if (o_.filter.noise.motion_noise == MotionNoise::Increment)
    p.cov.topLeftCorner<6, 6>() = k.cov;
  return p;
}

std::vector<FusedEstimator::ObservationResult> FusedEstimator::addFrame(const MotionSample &row,
                                                                        const std::vector<FeatureObservation> &observations)
{
  // The streaming form of validateInputs()'s frame order (frames arrive one at a time).
  if (started_ && row.frame <= last_.frame)
    throw Error("fused: frame " + std::to_string(row.frame) + " does not follow frame " + std::to_string(last_.frame));
  const std::vector<UndistortedObservation> obs = undistortObservations(camera_, o_.filter.noise.sigma_px, observations);
  std::vector<ObservationResult> results = initialResults(obs);

  if (started_)
    advanceKeys(row);
  else
    started_ = true;
  last_ = row;

  // A feature (re)starts at an observation: that frame is its key.
  auto restart = [&](Feature &f, const UndistortedObservation &o) {
    f.current.initialize(row.frame, row.yaw, o.m, o.cov);
    f.consecutive_outliers = 0;
    setKey(f, row.frame);
  };

  std::map<long, std::size_t> observed = usableObservations(obs);
  for (auto it = features_.begin(); it != features_.end();) {
    Feature &f = it->second;
    const auto o = observed.find(it->first);
    if (o != observed.end()) {
      const std::size_t i = o->second;
      const UndistortedObservation &ob = obs[i];
      observed.erase(o); // what is left in `observed` afterwards are the new features
      Key &k = keys_.at(f.key_frame);
      if (k.inc_frame != row.frame) {
        k.inc = IncrementModel::between(rig_, k.row, row);
        k.inc_frame = row.frame;
      }
      const IncrementPrior prior = keyPrior(k, f.key);
      f.current = f.key;
      const DepthFilter::Update u = f.current.step(k.inc, &ob.m, &ob.cov, &prior);
      results[i].update = u;
      f.last_seen = row.frame;
      const KeyChange change = keyChangeAfter(u, f.consecutive_outliers, f.current, f.key, o_);
      if (change == KeyChange::Restart) {
        restart(f, ob);
        results[i].update = DepthFilter::Update::Restarted;
      } else if (change == KeyChange::NewKey) {
        setKey(f, row.frame);
      }
    }
    if (row.frame - f.last_seen > o_.max_missing_frames) {
      dropKey(f.key_frame);
      it = features_.erase(it);
    } else {
      ++it;
    }
  }
  // New features.
  for (const auto &kv : observed) {
    const UndistortedObservation &o = obs[kv.second];
    Feature f{DepthFilter(o_.filter, camera_.kx(), camera_.ky()), DepthFilter(o_.filter, camera_.kx(), camera_.ky())};
    f.key_frame = -1;
    f.last_seen = row.frame;
    f.current.initialize(row.frame, row.yaw, o.m, o.cov);
    setKey(f, row.frame);
    features_.emplace(kv.first, std::move(f));
  }
  return results;
}

} // namespace yawdepth
