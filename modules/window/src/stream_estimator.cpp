#include <yawdepth/window/stream_estimator.h>

#include <cmath>
#include <string>
#include <yawdepth/error.h>

namespace yawdepth {

WindowOptions windowOptions(const StreamOptions &options)
{
  WindowOptions w;
  w.noise = options.noise;
  w.gates = options.gates;
  w.window = options.window;
  w.robust_threshold_px = options.robust_threshold_px;
  w.outlier_threshold_px = options.outlier_threshold_px;
  w.prior_inverse_depth = 1.0 / options.prior_depth;
  return w;
}

FusedOptions fusedOptions(const StreamOptions &options)
{
  FusedOptions f;
  f.filter.noise = options.noise;
  f.filter.gates = options.gates;
  f.filter.prior_depth = options.prior_depth;
  f.max_missing_frames = options.max_missing_frames;
  return f;
}

StreamEstimator::StreamEstimator(const CameraModel &camera, const YawRig &rig, const StreamOptions &options)
    : rig_(rig), options_(options)
{
  if (!(std::isfinite(options.prior_depth) && options.prior_depth > 0))
    throw Error("stream estimator: prior_depth must be finite and positive");
  options.noise.validateFor(toMethod(options.method));
  if (options.method == StreamMethod::Window)
    window_ = std::make_unique<WindowEstimator>(camera, rig, windowOptions(options));
  else
    fused_ = std::make_unique<FusedEstimator>(camera, rig, fusedOptions(options));
}

void StreamEstimator::addFrame(const MotionSample &row, const std::vector<FeatureObservation> &observations)
{
  if (window_)
    window_->addFrame(row, observations);
  else
    fused_->addFrame(row, observations);
  rows_[row.frame] = row;
  // A feature's estimate is kept at its last observed frame while the estimator keeps it: in the
  // window, or up to max_missing_frames for fused.
  const long keep = window_ ? options_.window : static_cast<long>(options_.max_missing_frames) + 1;
  while (!rows_.empty() && rows_.begin()->first <= row.frame - keep)
    rows_.erase(rows_.begin());
}

PointEstimate StreamEstimator::estimate(long id) const { return window_ ? window_->estimate(id) : fused_->estimate(id); }

PointEstimate StreamEstimator::estimateAt(long id, const MotionSample &pose) const
{
  PointEstimate e = estimate(id);
  if (!e.ok())
    return e;
  const auto it = rows_.find(e.frame);
  if (it == rows_.end()) { // older than the rows kept: not usable at this pose
    e.status = Status::TooFewFrames;
    return e;
  }
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  fromVisp(curMprev(rig_, it->second, pose), R, t);
  e.c_P = R * e.c_P + t;
  e.c_cov = R * e.c_cov * R.transpose();
  e.v_P = rig_.visionPoint(pose.yaw, e.c_P);
  if (!(e.c_P.z() > 0))
    e.status = Status::Behind;
  return e;
}

void StreamEstimator::forget(long id)
{
  if (window_)
    window_->forget(id);
  else
    fused_->forget(id);
}

} // namespace yawdepth
