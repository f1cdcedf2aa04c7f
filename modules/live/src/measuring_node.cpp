#include <yawdepth/live/measuring_node.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

std::string nodeNumber(double v)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", v);
  return text;
}

// To 2 decimals, without a "-0.00".
double nodeRounded(double v) { return std::round(v * 100.0) / 100.0 + 0.0; }

} // namespace

void MeasuringNodeSettings::validate() const
{
  if (motion != "tf" && motion != "odom")
    throw Error("motion: '" + motion + "' (tf or odom)");
  if (motion == "tf" && (world_frame.empty() || body_frame.empty() || world_frame == body_frame))
    throw Error("world_frame, body_frame: two different frames are needed with motion tf");
  try {
    panJointFrame(joint_axis, joint_origin);
  } catch (const Error &e) {
    throw Error(std::string("joint_axis, joint_origin: ") + e.what());
  }
  if (!std::isfinite(camera_latency))
    throw Error("camera_latency: must be finite");
  if (!std::isfinite(interval_sigmas) || interval_sigmas < 0)
    throw Error("interval_sigmas: must be finite and not negative");
  if (!std::isfinite(diagnostics_period) || !(diagnostics_period > 0))
    throw Error("diagnostics_period: must be positive");
  if (!std::isfinite(service_wait) || service_wait < 0)
    throw Error("service_wait: must be finite and not negative");
  onlineOptions().validate();
  providerOptions().validate();
}

DepthProviderOptions MeasuringNodeSettings::providerOptions() const
{
  DepthProviderOptions p; // its own noise model (per control period) and convergence rules
  p.method = online.method;
  p.window = online.window;
  p.prior_depth = online.prior_depth;
  return p;
}

OnlineOptions MeasuringNodeSettings::onlineOptions() const
{
  OnlineOptions o = online;
  o.time_offset = -camera_latency; // the image stamped t was exposed at motion time t - latency
  return o;
}

MeasuringNode::MeasuringNode(const MeasuringNodeSettings &settings) : settings_(settings)
{
  settings_.validate();
}

MeasuringNode::~MeasuringNode() = default;

bool MeasuringNode::setCameraInfo(const CameraInfoMessage &info, const std::string &topic)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (!info_) {
    cameraFromCameraInfo(info, topic); // refused now, with its reason, when bad
    info_ = info;
    info_topic_ = topic;
    return true;
  }
  return sameCalibration(*info_, info);
}

void MeasuringNode::setOdometryFrames(const std::string &world, const std::string &body, const std::string &topic)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (odom_body_.empty()) {
    if (body.empty())
      throw Error(topic + ": the odometry has no child_frame_id: the body frame is unknown");
    odom_world_ = world;
    odom_body_ = body;
  } else if (body != odom_body_ || world != odom_world_) {
    throw Error(topic + ": the pose of " + body + " in " + world + ", where the first message gave " + odom_body_ +
                " in " + odom_world_);
  }
}

std::string MeasuringNode::bodyFrame() const
{
  if (settings_.motion == "tf")
    return settings_.body_frame;
  if (started_) // set once before started_: no lock (a transform lookup under motion_mutex_ calls this)
    return body_frame_;
  std::lock_guard<std::mutex> lock(mutex_);
  return odom_body_;
}

std::string MeasuringNode::worldFrame() const
{
  if (settings_.motion == "tf")
    return settings_.world_frame;
  std::lock_guard<std::mutex> lock(mutex_);
  return odom_world_;
}

std::string MeasuringNode::start(const std::string &image_frame,
                                 const std::function<MountLookup(const std::string &, const std::string &)> &mount)
{
  if (started_)
    return "";
  const std::string body = bodyFrame(), world = worldFrame();
  std::lock_guard<std::mutex> lock(mutex_);
  if (started_)
    return "";
  const std::string camera = settings_.camera_frame.empty() ? image_frame : settings_.camera_frame;
  waiting_ = !info_           ? "waiting for camera_info"
             : camera.empty() ? "the images have no frame_id: set camera_frame"
             : body.empty()   ? "waiting for the odometry (its child_frame_id is the body)"
                              : "";
  if (!waiting_.empty()) {
    if (camera.empty() && info_)
      throw Error(waiting_);
    return waiting_;
  }
  // The mount: fixed on the static transforms; or moving (a pan link published from the joint
  // states), when the camera's own pose is the motion, as import-bag does.
  vpHomogeneousMatrix bMc;
  bool moving = false;
  if (body != camera) {
    const MountLookup m = mount(body, camera);
    if (m.fixed)
      bMc = *m.fixed;
    else if (m.moving)
      moving = true;
    else
      return waiting_ = "waiting for the camera mount " + body + " -> " + camera + " on /tf_static" +
                        (m.why.empty() ? std::string() : " (" + m.why + ")");
  }
  const bool pan = !settings_.joint.empty() && !moving;
  bMv_ = pan ? panJointFrame(settings_.joint_axis, settings_.joint_origin) : vpHomogeneousMatrix();
  rig_ = std::make_unique<YawRig>(moving ? YawRig() : YawRig(bMv_.inverse() * bMc));
  const CameraModel camera_model = cameraFromCameraInfo(*info_, info_topic_);
  online_ = settings_.onlineOptions();
  online_.wait_for_joints = pan; // never measured at the poses' yaw while the joint readings have not come
  camera_ = std::make_unique<CameraModel>(camera_model);
  std::atomic_store(&measurer_, std::make_shared<OnlineMeasurer>(*camera_, *rig_, online_));
  provider_ = std::make_unique<DepthProvider>(*camera_, *rig_, settings_.providerOptions());
  camera_frame_ = camera;
  body_frame_ = body;
  world_frame_ = world;
  moving_mount_ = moving;
  last_diagnostics_ = std::chrono::steady_clock::now();
  started_ = true;
  return "";
}

void MeasuringNode::pushImage(double t, const cv::Mat &gray)
{
  if (started_)
    measurer()->pushImage(t, gray);
}

void MeasuringNode::pushMotion(double t, const vpHomogeneousMatrix &wMb, const vpHomogeneousMatrix &bMc_t)
{
  if (started_)
    measurer()->pushPose(t, MotionSample::fromPose(0, wMb * bMv_ * bMc_t));
}

void MeasuringNode::queueMotion(double t, std::uint64_t tag, const std::optional<vpHomogeneousMatrix> &wMb)
{
  if (!started_ || !std::isfinite(t))
    return;
  std::lock_guard<std::mutex> lock(motion_mutex_);
  if (!(t > last_pushed_t_))
    return; // the measurer would refuse it (out of order)
  // In time order: a stamp ahead of the others (a post-dated transform) waits at the end while the
  // earlier ones go through.
  const auto at = std::upper_bound(pending_motion_.begin(), pending_motion_.end(), t,
                                   [](double v, const PendingMotion &p) { return v < p.t; });
  if (at != pending_motion_.begin() && std::prev(at)->t == t)
    return; // the sample queued at this time stands for it (its lookup sees every transform by then)
  pending_motion_.insert(at, {t, tag, wMb});
  const double keep_from = pending_motion_.back().t - online_.max_image_age; // older: no image would wait for it
  while (pending_motion_.front().t < keep_from) {
    pending_motion_.pop_front();
    ++unresolved_motion_;
  }
}

std::size_t MeasuringNode::resolveMotion(const TransformAt &transform_at)
{
  if (!started_)
    return 0;
  std::lock_guard<std::mutex> lock(motion_mutex_);
  std::size_t pushed = 0;
  for (std::size_t i = 0; i < pending_motion_.size();) {
    const std::optional<vpHomogeneousMatrix> X = transform_at(pending_motion_[i].t, pending_motion_[i].tag);
    if (!X) {
      ++i;
      continue;
    }
    const PendingMotion p = pending_motion_[i];
    unresolved_motion_ += i; // the earlier ones never will be: the transforms cover a later time, not theirs
    pending_motion_.erase(pending_motion_.begin(), pending_motion_.begin() + static_cast<std::ptrdiff_t>(i) + 1);
    i = 0;
    last_pushed_t_ = p.t;
    if (p.wMb) // out of the queue first: a push that throws (a bad pose) is not retried
      pushMotion(p.t, *p.wMb, *X);
    else
      pushMotion(p.t, *X);
    ++pushed;
  }
  return pushed;
}

bool MeasuringNode::pushJointState(double t, const std::vector<std::string> &names, const std::vector<double> &positions,
                                   const std::string &topic)
{
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] != settings_.joint)
      continue;
    if (i >= positions.size())
      throw Error(topic + ": joint " + settings_.joint + " has no position (" + std::to_string(positions.size()) +
                  " positions for " + std::to_string(names.size()) + " names)");
    if (started_ && !moving_mount_) // with a moving mount, the pan is in the camera's pose already
      measurer()->pushJoint(t, positions[i]);
    return true;
  }
  return false;
}

void MeasuringNode::restart()
{
  if (!started_)
    return;
  // motion_mutex_ first (as resolveMotion() holds it while pushing): no sample of the old clock is
  // pushed into the new measurer.
  std::lock_guard<std::mutex> motion_lock(motion_mutex_);
  pending_motion_.clear();
  last_pushed_t_ = -std::numeric_limits<double>::infinity();
  std::lock_guard<std::mutex> lock(mutex_);
  std::atomic_store(&measurer_, std::make_shared<OnlineMeasurer>(*camera_, *rig_, online_));
  {
    std::lock_guard<std::mutex> provider_lock(provider_mutex_);
    provider_ = std::make_unique<DepthProvider>(*camera_, *rig_, settings_.providerOptions());
  }
  last_dropped_ = 0;
  frames_ = 0;
  latencies_ms_.clear();
  ++restarts_;
}

std::vector<OnlineFrame> MeasuringNode::process()
{
  if (!started_)
    return {};
  std::vector<OnlineFrame> frames = measurer()->process();
  std::lock_guard<std::mutex> lock(mutex_);
  for (const OnlineFrame &f : frames) {
    ++frames_;
    latencies_ms_.push_back(f.latency_ms);
    last_counts_ = countByStatus(f);
  }
  return frames;
}

std::vector<CloudPoint> MeasuringNode::cloud(const OnlineFrame &frame)
{
  std::vector<CloudPoint> c = frameCloud(frame, *rig_, settings_.interval_sigmas);
  std::lock_guard<std::mutex> lock(mutex_);
  last_cloud_ = c.size();
  return c;
}

NodeDiagnostics MeasuringNode::diagnostics()
{
  NodeDiagnostics d;
  auto add = [&d](const std::string &k, const std::string &v) { d.values.emplace_back(k, v); };
  const std::size_t bad_total = bad_messages_;
  std::lock_guard<std::mutex> lock(mutex_);
  const std::size_t bad = bad_total - last_bad_; // in this period
  last_bad_ = bad_total;
  if (!started_) {
    d.warn = true;
    d.message = waiting_.empty() ? "waiting for the first image" : waiting_;
    add("bad messages", std::to_string(bad_total));
    return d;
  }
  const OnlineStats st = measurer()->stats();
  const auto now = std::chrono::steady_clock::now();
  const double period = std::chrono::duration<double>(now - last_diagnostics_).count();
  last_diagnostics_ = now;
  const std::size_t dropped = st.dropped_stale + st.dropped_uncovered + st.dropped_overflow;
  const bool dropping = dropped > last_dropped_;
  last_dropped_ = dropped;
  // The body turning about another axis than the pan's: a wrong joint_axis (or mount), which the data
  // reveal (TurnAxis, as import-bag's warning).
  std::string off_axis;
  if (st.turns_off_pan_axis) {
    const Eigen::Vector3d v_axis = st.turn_axis.normalized();
    Eigen::Vector3d b_axis;
    for (unsigned i = 0; i < 3; ++i)
      b_axis[i] = bMv_[i][0] * v_axis[0] + bMv_[i][1] * v_axis[1] + bMv_[i][2] * v_axis[2];
    char text[200];
    std::snprintf(text, sizeof text,
                  "the body turns about (%.2f, %.2f, %.2f) in the body frame, not about joint_axis: check "
                  "joint_axis (REP 103's base_link: [0, 0, 1]) and joint_origin",
                  nodeRounded(b_axis.x()), nodeRounded(b_axis.y()), nodeRounded(b_axis.z()));
    off_axis = text;
  }
  // The mistakes the streams reveal: no joint readings for a pan rig; image stamps far from the
  // motion's (a wrong camera_latency, another clock).
  std::string reason = off_axis;
  const bool pan = !settings_.joint.empty() && !moving_mount_;
  if (reason.empty() && pan && st.joint_readings == 0 && st.images_pushed > 0)
    reason = "no readings of the pan joint " + settings_.joint + " yet: check the joint states topic and joint";
  const double ahead = st.image_ahead_of_poses, max_age = settings_.online.max_image_age;
  if (reason.empty() && dropping && std::isfinite(ahead) && std::abs(ahead) > max_age)
    reason = "images dropped: their stamps are " + nodeNumber(std::abs(ahead)) + " s " +
             (ahead > 0 ? "ahead of" : "behind") + " the motion's: check camera_latency and the clocks";
  d.warn = dropping || bad > 0 || !reason.empty();
  d.message = !reason.empty() ? reason : dropping ? "images dropped" : bad > 0 ? "bad messages" : "measuring";
  add("images pushed", std::to_string(st.images_pushed));
  add("images measured", std::to_string(st.images_measured));
  add("measured rate (Hz)", nodeNumber(double(frames_) / std::max(period, 1e-9)));
  add("dropped stale", std::to_string(st.dropped_stale));
  add("dropped uncovered", std::to_string(st.dropped_uncovered));
  add("dropped overflow", std::to_string(st.dropped_overflow));
  add("out of order (images, poses, joints)", std::to_string(st.out_of_order_images) + ", " +
                                                  std::to_string(st.out_of_order_poses) + ", " +
                                                  std::to_string(st.out_of_order_joints));
  add("queued images", std::to_string(st.queued_images));
  add("motion dropped (no transform)", std::to_string(unresolved_motion_.load()));
  std::vector<double> l = latencies_ms_;
  std::sort(l.begin(), l.end());
  if (!l.empty()) { // none without an image measured in the period
    add("latency median (ms)", nodeNumber(l[l.size() / 2]));
    add("latency max (ms)", nodeNumber(l.back()));
  }
  add("joint readings", std::to_string(st.joint_readings));
  if (std::isfinite(ahead))
    add("image stamps ahead of the motion (s)", nodeNumber(ahead));
  add("points published (last image)", std::to_string(last_cloud_));
  for (const auto &[status, n] : last_counts_)
    add(std::string("points ") + toString(status) + " (last image)", std::to_string(n));
  add("bad messages", std::to_string(bad_total));
  add("restarts (time jumped back)", std::to_string(restarts_));
  frames_ = 0;
  latencies_ms_.clear();
  return d;
}

ServoDepthAnswer MeasuringNode::depths(const ServoDepthRequest &r)
{
  ServoDepthAnswer a;
  try {
    if (!started_)
      throw Error("not measuring yet (waiting for camera_info, the camera mount or the motion)");
    if (r.u.size() != r.ids.size() || r.v.size() != r.ids.size())
      throw Error("ids, u and v must have the same length");
    const std::shared_ptr<OnlineMeasurer> m = measurer();
    const double t_motion = r.t + m->options().time_offset;
    MotionSample pose;
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(settings_.service_wait);
    for (;;) {
      const OnlineMeasurer::Coverage c = m->poseAt(t_motion, pose);
      if (c == OnlineMeasurer::Coverage::Covered)
        break;
      if (c == OnlineMeasurer::Coverage::Never)
        throw Error("no motion at t = " + nodeNumber(r.t) + " s: older than the motion kept (max_image_age), or in a gap");
      if (std::chrono::steady_clock::now() >= until)
        throw Error("no motion around t = " + nodeNumber(r.t) +
                    " s yet (the pose or joint streams do not cover it, within service_wait)");
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    std::vector<std::pair<long, vpImagePoint>> points;
    points.reserve(r.ids.size());
    for (std::size_t i = 0; i < r.ids.size(); ++i)
      points.emplace_back(r.ids[i], vpImagePoint(r.v[i], r.u[i]));
    std::lock_guard<std::mutex> lock(provider_mutex_);
    provider_->update(pose, points);
    for (long id : r.ids)
      a.depths.push_back(provider_->info(id));
  } catch (const std::exception &e) {
    a.depths.clear();
    a.error = e.what();
  }
  return a;
}

} // namespace yawdepth
