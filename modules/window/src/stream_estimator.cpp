#include <yawdepth/window/stream_estimator.h>

#include <string>
#include <yawdepth/error.h>

namespace yawdepth {

StreamEstimator::StreamEstimator(const CameraModel &camera, const YawRig &rig, const StreamOptions &options)
    : rig_(rig), options_(options)
{
  if (options.method == Method::Window)
    window_ = std::make_unique<WindowEstimator>(camera, rig, options.window);
  else if (options.method == Method::Fused)
    fused_ = std::make_unique<FusedEstimator>(camera, rig, options.fused);
  else
    throw Error(std::string("stream estimator: method ") + toString(options.method) +
                " does not run frame by frame (fused or window do)");
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
  const long keep = window_ ? options_.window.window : static_cast<long>(options_.fused.max_missing_frames) + 1;
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
    fused_->remove(id);
}

} // namespace yawdepth
