#include <yawdepth/online/online_measurer.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

bool onlineFinitePositive(double v) { return std::isfinite(v) && v > 0; }

StreamOptions onlineStreamOptions(const OnlineOptions &o)
{
  o.validate();
  StreamOptions s;
  s.method = o.method;
  s.noise = o.noise;
  s.window = o.window;
  s.prior_depth = o.prior_depth;
  return s;
}

bool onlineFiniteRow(const MotionSample &r)
{
  return std::isfinite(r.x) && std::isfinite(r.y) && std::isfinite(r.z) && std::isfinite(r.heading) &&
         std::isfinite(r.yaw) && r.theta_u.allFinite();
}

double onlineMs(std::chrono::steady_clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

// Where time `t` falls in a buffer sorted by strictly increasing time: 1 when the buffer's last time is
// before it (wait for more), -1 when it cannot be covered (before the first, or in a gap over `max_gap`),
// 0 when covered: `lo`, `hi` the entries around it and `s` the fraction between them.
template <typename Entry>
int onlineBracket(const std::deque<Entry> &buffer, double t, double max_gap, std::size_t &lo, std::size_t &hi, double &s)
{
  if (buffer.empty() || t > buffer.back().first)
    return 1;
  if (t < buffer.front().first)
    return -1;
  const auto it = std::upper_bound(buffer.begin(), buffer.end(), t,
                                   [](double v, const Entry &e) { return v < e.first; }); // first entry after t
  const std::size_t j = static_cast<std::size_t>(it - buffer.begin());                   // >= 1
  if (buffer[j - 1].first == t) {
    lo = hi = j - 1;
    s = 0;
    return 0;
  }
  if (buffer[j].first - buffer[j - 1].first > max_gap)
    return -1;
  lo = j - 1;
  hi = j;
  s = (t - buffer[lo].first) / (buffer[hi].first - buffer[lo].first);
  return 0;
}

// Drops the entries before the last one at or before `t` (it and later ones stay: an image at `t` or
// later needs them).
template <typename Entry> void onlineTrim(std::deque<Entry> &buffer, double t)
{
  while (buffer.size() >= 2 && buffer[1].first <= t)
    buffer.pop_front();
}

} // namespace

void OnlineOptions::validate() const
{
  if (method != StreamMethod::Window && method != StreamMethod::Fused)
    throw Error("online options: method must be window or fused");
  noise.validateFor(method == StreamMethod::Window ? Method::Window : Method::Fused);
  if (window < 2)
    throw Error("online options: window must be at least 2 frames");
  if (!onlineFinitePositive(prior_depth))
    throw Error("online options: prior_depth must be finite and positive");
  klt.validate();
  if (!std::isfinite(time_offset))
    throw Error("online options: time_offset must be finite");
  if (!onlineFinitePositive(max_pose_gap))
    throw Error("online options: max_pose_gap must be finite and positive");
  if (!onlineFinitePositive(max_image_age))
    throw Error("online options: max_image_age must be finite and positive");
  if (max_queued_images < 1)
    throw Error("online options: max_queued_images must be at least 1");
}

struct OnlineMeasurer::Job {
  QueuedImage image;
  MotionSample pose;
  Clock::time_point taken;
};

OnlineMeasurer::OnlineMeasurer(const CameraModel &camera, const YawRig &rig, const OnlineOptions &options)
    : camera_(camera), rig_(rig), options_(options), last_image_t_(-std::numeric_limits<double>::infinity()),
      last_pose_t_(-std::numeric_limits<double>::infinity()), last_joint_t_(-std::numeric_limits<double>::infinity()),
      newest_t_(-std::numeric_limits<double>::infinity()),
      tracker_(camera, options.klt), estimator_(camera, rig, onlineStreamOptions(options))
{
  if (camera.width() == 0 || camera.height() == 0)
    throw Error("online measurer: the camera has no image size");
}

OnlineMeasurer::~OnlineMeasurer() = default;

void OnlineMeasurer::noteTime(double t_motion) { newest_t_ = std::max(newest_t_, t_motion); }

void OnlineMeasurer::pushImage(double t, const cv::Mat &gray)
{
  const Clock::time_point pushed = Clock::now();
  if (!std::isfinite(t))
    throw Error("online measurer: pushImage: the image time is not finite");
  if (gray.type() != CV_8UC1)
    throw Error("online measurer: pushImage: the image must be 8-bit single channel (CV_8UC1), not type " +
                std::to_string(gray.type()) + " with " + std::to_string(gray.channels()) + " channels");
  if (gray.cols != static_cast<int>(camera_.width()) || gray.rows != static_cast<int>(camera_.height()))
    throw Error("online measurer: pushImage: the image is " + std::to_string(gray.cols) + "x" +
                std::to_string(gray.rows) + " but the camera is " + std::to_string(camera_.width()) + "x" +
                std::to_string(camera_.height()));
  QueuedImage q;
  q.t = t;
  q.gray = gray.clone(); // outside the lock: the caller may reuse its buffer
  q.pushed = pushed;
  std::lock_guard<std::mutex> lock(queue_mutex_);
  if (!(t > last_image_t_)) {
    ++stats_.out_of_order_images;
    return;
  }
  last_image_t_ = t;
  noteTime(t + options_.time_offset);
  if (!poses_.empty())
    stats_.image_ahead_of_poses = t + options_.time_offset - last_pose_t_;
  if (images_.size() >= static_cast<std::size_t>(options_.max_queued_images)) {
    images_.pop_front();
    ++stats_.dropped_overflow;
  }
  images_.push_back(std::move(q));
  ++stats_.images_pushed;
}

void OnlineMeasurer::pushPose(double t, const MotionSample &row)
{
  if (!std::isfinite(t))
    throw Error("online measurer: pushPose: the pose time is not finite");
  if (!onlineFiniteRow(row))
    throw Error("online measurer: pushPose: the pose at t = " + std::to_string(t) + " has a non-finite value");
  std::lock_guard<std::mutex> lock(queue_mutex_);
  if (have_pose_form_ && row.six_dof != six_dof_)
    throw Error(std::string("online measurer: pushPose: a ") + (row.six_dof ? "6-DoF" : "planar") +
                " pose after " + (six_dof_ ? "6-DoF" : "planar") + " ones (one form per stream)");
  if (!(t > last_pose_t_)) {
    ++stats_.out_of_order_poses;
    return;
  }
  appendPoseLocked(t, row);
}

void OnlineMeasurer::pushOdometryIncrement(double t, const vpHomogeneousMatrix &vprevMvcur)
{
  if (!std::isfinite(t))
    throw Error("online measurer: pushOdometryIncrement: the increment time is not finite");
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 4; ++j)
      if (!std::isfinite(vprevMvcur[i][j]))
        throw Error("online measurer: pushOdometryIncrement: the increment at t = " + std::to_string(t) +
                    " has a non-finite value");
  Eigen::Matrix3d dR;
  Eigen::Vector3d d;
  fromVisp(vprevMvcur, dR, d);
  const Eigen::Vector3d turn = logSO3(dR);
  std::lock_guard<std::mutex> lock(queue_mutex_);
  if (poses_.empty()) // trimming keeps the newest pose: empty only before the first
    throw Error("online measurer: pushOdometryIncrement: no pose to start from (push a first one with pushPose)");
  if (!(t > last_pose_t_)) {
    ++stats_.out_of_order_poses;
    return;
  }
  const MotionSample &last = poses_.back().second;
  MotionSample next = last;
  if (!last.six_dof) {
    if (std::hypot(turn.x(), turn.z()) > 1e-9)
      throw Error("online measurer: pushOdometryIncrement: a planar pose stream takes increments turning about +Y "
                  "only (this one turns " + std::to_string(std::hypot(turn.x(), turn.z())) + " rad about X/Z)");
    const Eigen::Vector3d w_d = rotY(last.heading) * d;
    next.x += w_d.x();
    next.y += w_d.y();
    next.z += w_d.z();
    next.heading += turn.y();
  } else {
    next = MotionSample::fromPose(last.frame, wMv(last) * vprevMvcur, last.yaw);
  }
  appendPoseLocked(t, next);
}

void OnlineMeasurer::appendPoseLocked(double t, const MotionSample &row)
{
  have_pose_form_ = true;
  six_dof_ = row.six_dof;
  last_pose_t_ = t;
  noteTime(t);
  turn_.add(row.rotation());
  poses_.emplace_back(t, row);
  trimBuffers();
}

void OnlineMeasurer::pushJoint(double t, double yaw)
{
  if (!std::isfinite(t))
    throw Error("online measurer: pushJoint: the joint time is not finite");
  if (!std::isfinite(yaw))
    throw Error("online measurer: pushJoint: the yaw at t = " + std::to_string(t) + " is not finite");
  std::lock_guard<std::mutex> lock(queue_mutex_);
  if (!(t > last_joint_t_)) {
    ++stats_.out_of_order_joints;
    return;
  }
  joints_pushed_ = true;
  ++stats_.joint_readings;
  last_joint_t_ = t;
  noteTime(t);
  joints_.emplace_back(t, yaw);
  trimBuffers();
}

// Bounded: an image (or a poseAt() time) more than max_image_age behind the newest time is never
// measured, so the poses and joint readings before it are dropped (the one at or before it stays).
void OnlineMeasurer::trimBuffers()
{
  const double keep_from = newest_t_ - options_.max_image_age;
  onlineTrim(poses_, keep_from);
  onlineTrim(joints_, keep_from);
}

// Under queue_mutex_: the motion-log row at motion time `tm` (see motionAtLocked's declaration).
int OnlineMeasurer::motionAtLocked(double tm, MotionSample &pose) const
{
  std::size_t lo = 0, hi = 0;
  double s = 0;
  const int pose_at = onlineBracket(poses_, tm, options_.max_pose_gap, lo, hi, s);
  if (pose_at != 0)
    return pose_at;
  pose = lo == hi ? poses_[lo].second : interpolateMotion(poses_[lo].second, poses_[hi].second, s);
  if (!joints_pushed_ && !options_.wait_for_joints)
    return 0;
  std::size_t jlo = 0, jhi = 0;
  double js = 0;
  const int joint_at = onlineBracket(joints_, tm, options_.max_pose_gap, jlo, jhi, js);
  if (joint_at != 0)
    return joint_at;
  if (jlo == jhi) {
    pose.yaw = joints_[jlo].second;
  } else { // interpolateMotion()'s yaw: linear along the shorter way round
    MotionSample a, b;
    a.yaw = joints_[jlo].second;
    b.yaw = joints_[jhi].second;
    pose.yaw = interpolateMotion(a, b, js).yaw;
  }
  return 0;
}

OnlineMeasurer::Coverage OnlineMeasurer::poseAt(double t_motion, MotionSample &pose) const
{
  if (!std::isfinite(t_motion))
    throw Error("online measurer: poseAt: the time is not finite");
  std::lock_guard<std::mutex> lock(queue_mutex_);
  MotionSample p;
  const int at = motionAtLocked(t_motion, p);
  if (at != 0)
    return at > 0 ? Coverage::NotYet : Coverage::Never;
  pose = p;
  return Coverage::Covered;
}

// Under queue_mutex_: the oldest image that can be measured now, its pose interpolated; drops the stale
// and uncovered ones on the way. False when none is ready.
bool OnlineMeasurer::nextJob(Job &job)
{
  while (!images_.empty()) {
    const QueuedImage &front = images_.front();
    const double tm = front.t + options_.time_offset;
    if (newest_t_ - tm > options_.max_image_age) {
      images_.pop_front();
      ++stats_.dropped_stale;
      continue;
    }
    MotionSample pose;
    const int at = motionAtLocked(tm, pose);
    if (at < 0) {
      images_.pop_front();
      ++stats_.dropped_uncovered;
      continue;
    }
    if (at > 0)
      return false; // wait for the poses (joint readings) after it (the later images wait behind it)
    job.image = std::move(images_.front());
    images_.pop_front();
    job.pose = pose;
    job.taken = Clock::now();
    return true;
  }
  return false;
}

std::vector<OnlineFrame> OnlineMeasurer::process()
{
  std::lock_guard<std::mutex> work(work_mutex_);
  std::vector<OnlineFrame> out;
  for (;;) {
    Job job;
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      if (!nextJob(job))
        break;
    }
    OnlineFrame f;
    f.t = job.image.t;
    f.t_motion = job.image.t + options_.time_offset;
    job.pose.frame = next_frame_++;
    f.frame = job.pose.frame;
    f.pose = job.pose;
    f.image = job.image.gray;
    f.ahead_ms = tracker_.prepared(job.image.gray) ? ahead_ms_ : 0.0;
    const Clock::time_point t0 = Clock::now();
    std::vector<FeatureObservation> observations;
    if (have_previous_) {
      const KltMotion m = kltMotion(rig_, previous_, job.pose, options_.noise);
      observations = tracker_.track(job.image.gray, &m);
    } else {
      observations = tracker_.track(job.image.gray, nullptr);
    }
    for (long id : tracker_.lastAppearanceCuts()) // its earlier frames slid too: not one point
      estimator_.forget(id);
    const Clock::time_point t1 = Clock::now();
    estimator_.addFrame(job.pose, observations);
    f.points.reserve(observations.size());
    for (const FeatureObservation &o : observations) {
      OnlinePoint p;
      p.id = o.id;
      p.u = o.u;
      p.v = o.v;
      p.estimate = estimator_.estimate(o.id);
      f.points.push_back(p);
      last_seen_.emplace_back(o.id, f.frame);
    }
    // Bounded memory: forget the features not seen for longer than the estimator keeps frames.
    const long keep = std::max<long>(options_.window, 2) + 1;
    std::sort(last_seen_.begin(), last_seen_.end());
    std::vector<std::pair<long, long>> kept;
    kept.reserve(last_seen_.size());
    for (std::size_t i = 0; i < last_seen_.size(); ++i) {
      if (i + 1 < last_seen_.size() && last_seen_[i + 1].first == last_seen_[i].first)
        continue; // the latest (id, frame) of an id is its last
      if (f.frame - last_seen_[i].second > keep)
        estimator_.forget(last_seen_[i].first);
      else
        kept.push_back(last_seen_[i]);
    }
    last_seen_.swap(kept);
    const Clock::time_point t2 = Clock::now();
    previous_ = job.pose;
    have_previous_ = true;
    f.wait_ms = onlineMs(job.taken - job.image.pushed);
    f.track_ms = onlineMs(t1 - t0);
    f.estimate_ms = onlineMs(t2 - t1);
    f.latency_ms = onlineMs(t2 - job.image.pushed);
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      ++stats_.images_measured;
      stats_.last_latency_ms = f.latency_ms;
    }
    out.push_back(std::move(f));
  }
  // The oldest image waits for its motion: the tracking that needs none now, not after it comes. Only
  // in a call that measured nothing: the frames measured are returned without waiting for it (the
  // consumer's next call, at the next push, does it).
  cv::Mat waiting;
  if (out.empty()) {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (!images_.empty())
      waiting = images_.front().gray;
  }
  if (!waiting.empty() && !tracker_.prepared(waiting)) {
    const Clock::time_point a0 = Clock::now();
    tracker_.prepare(waiting);
    ahead_ms_ = onlineMs(Clock::now() - a0);
  }
  return out;
}

bool OnlineMeasurer::currentPose(MotionSample &pose) const
{
  std::lock_guard<std::mutex> lock(queue_mutex_);
  if (poses_.empty())
    return false;
  pose = poses_.back().second;
  if (joints_pushed_ && !joints_.empty())
    pose.yaw = joints_.back().second;
  return true;
}

std::vector<PointEstimate> OnlineMeasurer::depths(const std::vector<long> &ids) const
{
  MotionSample now;
  const bool have_pose = currentPose(now);
  std::lock_guard<std::mutex> work(work_mutex_);
  std::vector<PointEstimate> out;
  out.reserve(ids.size());
  for (long id : ids)
    out.push_back(have_pose ? estimator_.estimateAt(id, now) : PointEstimate());
  return out;
}

OnlineStats OnlineMeasurer::stats() const
{
  std::lock_guard<std::mutex> lock(queue_mutex_);
  OnlineStats s = stats_;
  s.queued_images = images_.size();
  s.buffered_poses = poses_.size();
  s.buffered_joints = joints_.size();
  s.turned = turn_.turned();
  s.turn_axis = turn_.sum();
  s.turns_off_pan_axis = (joints_pushed_ || options_.wait_for_joints) && turn_.offPanAxis();
  return s;
}

} // namespace yawdepth
