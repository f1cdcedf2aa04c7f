/*
  yawdepth_node: the ROS 1 adapter over yawdepth::MeasuringNode (yawdepth/live/measuring_node.h) and
  its OnlineMeasurer (issue 37; docs/ros.md gives the topics, parameters and frames). No logic of its
  own: parameters read into the library's settings, messages converted and pushed, the transforms
  looked up, measured frames converted and published. The settings, the start (camera, mount, pan
  frame), the motion, the timing rules, the cloud, the diagnostics and the servo requests are the
  library's, tested without ROS (test_live, test_online). A ROS 2 node is this file against rclcpp
  (docs/ros.md, "ROS 2").

  Threads: the callbacks run on an AsyncSpinner and only push (non-blocking); ~depths has its own
  queue and thread (a request waits up to ~service_wait for the motion around it); the main thread
  waits for pushes, calls process() and publishes.
*/
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <image_transport/image_transport.h>
#include <nav_msgs/Odometry.h>
#include <opencv2/imgcodecs.hpp>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <visualization_msgs/MarkerArray.h>
#include <visp3/core/vpQuaternionVector.h>
#include <visp3/core/vpTranslationVector.h>

#include <yawdepth/FeatureDepths.h> // generated from srv/FeatureDepths.srv
#include <yawdepth/error.h>
#include <yawdepth/live/measuring_node.h>

namespace {

using yawdepth::Error;

/* The ROS-only parameters (the others are MeasuringNodeSettings', docs/ros.md "Parameters"). */
struct RosParams {
  std::string image_transport = "raw";
  std::string camera_info_topic; // empty: the image topic's sibling
  bool publish_markers = true;
};

template <typename T> T param(const ros::NodeHandle &pnh, const std::string &key, const T &fallback)
{
  T value = fallback;
  if (pnh.hasParam(key) && !pnh.getParam(key, value))
    throw Error("~" + key + ": wrong type");
  return value;
}

Eigen::Vector3d vectorParam(const ros::NodeHandle &pnh, const std::string &key, const Eigen::Vector3d &fallback)
{
  if (!pnh.hasParam(key))
    return fallback;
  // A YAML list (a launch file's rosparam), or a string "[x, y, z]" / "x,y,z" (roscpp's command line
  // `_key:=[0,0,1]` gives a string).
  std::vector<double> v;
  std::string text;
  if (!pnh.getParam(key, v) && pnh.getParam(key, text)) {
    std::replace(text.begin(), text.end(), ',', ' ');
    text.erase(std::remove_if(text.begin(), text.end(), [](char ch) { return ch == '[' || ch == ']'; }), text.end());
    std::istringstream in(text);
    double x = 0;
    while (in >> x)
      v.push_back(x);
    if (!in.eof())
      v.clear();
  }
  if (v.size() != 3 || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
    throw Error("~" + key + ": must be a list of 3 numbers, e.g. [0, 0, 1]");
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

/* The node's parameters into the library's settings (their defaults the library's own); an invalid
   one is an Error naming it. */
yawdepth::MeasuringNodeSettings readSettings(const ros::NodeHandle &pnh)
{
  yawdepth::MeasuringNodeSettings c;
  c.motion = param(pnh, "motion", c.motion);
  c.world_frame = param(pnh, "world_frame", c.world_frame);
  c.body_frame = param(pnh, "body_frame", c.body_frame);
  c.camera_frame = param(pnh, "camera_frame", c.camera_frame);
  c.joint = param(pnh, "joint", c.joint);
  c.joint_axis = vectorParam(pnh, "joint_axis", c.joint_axis);
  c.joint_origin = vectorParam(pnh, "joint_origin", c.joint_origin);
  c.camera_latency = param(pnh, "camera_latency", c.camera_latency);
  c.interval_sigmas = param(pnh, "interval_sigmas", c.interval_sigmas);
  c.diagnostics_period = param(pnh, "diagnostics_period", c.diagnostics_period);
  c.service_wait = param(pnh, "service_wait", c.service_wait);
  yawdepth::OnlineOptions &o = c.online;
  try {
    o.method = yawdepth::streamMethodFromString(param(pnh, "method", std::string(yawdepth::toString(o.method))));
  } catch (const Error &e) {
    throw Error(std::string("~method: ") + e.what());
  }
  o.window = param(pnh, "window", o.window);
  o.prior_depth = param(pnh, "prior_depth", o.prior_depth);
  o.max_pose_gap = param(pnh, "max_pose_gap", o.max_pose_gap);
  o.max_image_age = param(pnh, "max_image_age", o.max_image_age);
  o.max_queued_images = param(pnh, "max_queued_images", o.max_queued_images);
  o.noise.sigma_px = param(pnh, "sigma_px", o.noise.sigma_px);
  o.noise.sigma_odom = param(pnh, "sigma_odom", o.noise.sigma_odom);
  o.noise.sigma_rot = param(pnh, "sigma_rot", o.noise.sigma_rot);
  o.noise.sigma_yaw = param(pnh, "sigma_yaw", o.noise.sigma_yaw);
  try {
    o.noise.motion_noise =
        yawdepth::motionNoiseFromString(param(pnh, "motion_noise", std::string(yawdepth::toString(o.noise.motion_noise))));
  } catch (const Error &e) {
    throw Error(std::string("~motion_noise: ") + e.what());
  }
  o.klt.max_features = param(pnh, "max_features", o.klt.max_features);
  o.klt.sigma_px = param(pnh, "track_sigma_px", o.klt.sigma_px);
  try {
    c.validate();
  } catch (const Error &e) {
    throw Error(std::string("~") + e.what());
  }
  return c;
}

vpHomogeneousMatrix toVisp(const geometry_msgs::Transform &t)
{
  vpQuaternionVector q(t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w);
  const double n = std::sqrt(q.sumSquare());
  if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-3)
    throw Error("a transform's quaternion is not a unit quaternion");
  return vpHomogeneousMatrix(vpTranslationVector(t.translation.x, t.translation.y, t.translation.z), q);
}

yawdepth::CameraInfoMessage toYawdepth(const sensor_msgs::CameraInfo &m)
{
  yawdepth::CameraInfoMessage c;
  c.header.frame_id = m.header.frame_id;
  c.height = m.height;
  c.width = m.width;
  c.distortion_model = m.distortion_model;
  c.D = m.D;
  std::copy(m.K.begin(), m.K.end(), c.K.begin());
  std::copy(m.R.begin(), m.R.end(), c.R.begin());
  std::copy(m.P.begin(), m.P.end(), c.P.begin());
  c.binning_x = m.binning_x;
  c.binning_y = m.binning_y;
  return c;
}

class YawdepthNode {
public:
  YawdepthNode() : pnh_("~"), node_(readSettings(pnh_)), it_(nh_)
  {
    ros_.image_transport = param(pnh_, "image_transport", ros_.image_transport);
    ros_.camera_info_topic = param(pnh_, "camera_info_topic", ros_.camera_info_topic);
    ros_.publish_markers = param(pnh_, "publish_markers", ros_.publish_markers);
    const yawdepth::MeasuringNodeSettings &s = node_.settings();
    // Inputs.
    std::string image_topic = nh_.resolveName("image");
    // `image:=/camera/image_raw/compressed` names the transport's topic: the image topic is its parent.
    if (ros_.image_transport == "compressed" && image_topic.size() > 11 &&
        image_topic.compare(image_topic.size() - 11, 11, "/compressed") == 0)
      image_topic = ros::names::parentNamespace(image_topic);
    if (ros_.image_transport == "compressed") {
      // Debian ships no image_transport plugin for compressed images: the CompressedImage topic read
      // directly, decoded by OpenCV (what the plugin does).
      compressed_sub_ = nh_.subscribe(image_topic + "/compressed", 5, &YawdepthNode::onCompressed, this,
                                      ros::TransportHints().tcpNoDelay());
    } else if (ros_.image_transport == "raw") {
      image_sub_ = it_.subscribe(image_topic, 5, &YawdepthNode::onImage, this);
    } else {
      throw Error("~image_transport: '" + ros_.image_transport + "' (raw or compressed)");
    }
    camera_info_topic_ = ros_.camera_info_topic.empty() ? siblingInfo(image_topic) : ros_.camera_info_topic;
    info_sub_ = nh_.subscribe(camera_info_topic_, 2, &YawdepthNode::onInfo, this);
    tf_static_sub_ = nh_.subscribe("/tf_static", 20, &YawdepthNode::onTfStatic, this);
    // /tf always: the motion with `motion: tf`, a moving mount's links with either.
    tf_sub_ = nh_.subscribe("/tf", 200, &YawdepthNode::onTf, this, ros::TransportHints().tcpNoDelay());
    if (s.motion == "odom")
      odom_sub_ = nh_.subscribe("odom", 200, &YawdepthNode::onOdometry, this, ros::TransportHints().tcpNoDelay());
    if (!s.joint.empty())
      joint_sub_ = nh_.subscribe("joint_states", 200, &YawdepthNode::onJoints, this, ros::TransportHints().tcpNoDelay());
    // Outputs. Queues of a second of images: a subscriber catching up after a burst loses no cloud.
    points_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("points", 30);
    points_camera_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("points_camera", 30);
    if (ros_.publish_markers)
      markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 5);
    tracks_pub_ = it_.advertise(pnh_.resolveName("tracks"), 2);
    diagnostics_pub_ = nh_.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 5);
    // ~depths on its own queue and thread: a request waiting for the motion around its stamp never
    // holds up the callbacks that push that motion.
    ros::NodeHandle service_nh("~");
    service_nh.setCallbackQueue(&service_queue_);
    depths_srv_ = service_nh.advertiseService("depths", &YawdepthNode::onDepths, this);
    ROS_INFO("yawdepth_node: images %s (%s), %s, motion from %s%s", image_topic.c_str(), ros_.image_transport.c_str(),
             camera_info_topic_.c_str(),
             s.motion == "tf" ? ("TF " + s.world_frame + " -> " + s.body_frame).c_str() : nh_.resolveName("odom").c_str(),
             s.joint.empty() ? "" : (", pan joint " + s.joint + " from " + nh_.resolveName("joint_states")).c_str());
  }

  /* The queue of ~depths (its own spinner, started by main). */
  ros::CallbackQueue &serviceQueue() { return service_queue_; }

  /* The consumer: process() whenever a push wakes it, publish what it measured, diagnostics. */
  void run()
  {
    ros::WallTime next_diagnostics = ros::WallTime::now() + ros::WallDuration(node_.settings().diagnostics_period);
    while (ros::ok()) {
      {
        std::unique_lock<std::mutex> lock(wake_mutex_);
        wake_.wait_for(lock, std::chrono::milliseconds(50), [this] { return woken_; });
        woken_ = false;
      }
      // The clock jumped back (a bag played again, `rosbag play` restarted): every stamp would be
      // out of order from now on; measure afresh.
      const ros::Time now = ros::Time::now();
      if (!last_now_.isZero() && now + ros::Duration(1.0) < last_now_) {
        ROS_WARN("yawdepth_node: the clock jumped back %.1f s (a bag played again?): measuring afresh",
                 (last_now_ - now).toSec());
        {
          // The moving transforms of the old clock go; the static ones stay (latched once: a simulator
          // reset does not publish them again).
          std::lock_guard<std::mutex> lock(statics_mutex_);
          tf_.clear();
          for (const auto &[child, t] : statics_)
            tf_.setTransform(t, "tf_static", true);
        }
        node_.restart();
      }
      last_now_ = now;
      guarded("measuring", [&] {
        for (const yawdepth::OnlineFrame &f : node_.process())
          guarded("publishing", [&] { publish(f); });
      });
      if (ros::WallTime::now() >= next_diagnostics) {
        publishDiagnostics();
        next_diagnostics = ros::WallTime::now() + ros::WallDuration(node_.settings().diagnostics_period);
      }
    }
  }

private:
  static std::string siblingInfo(const std::string &image_topic)
  {
    const std::string parent = ros::names::parentNamespace(image_topic);
    return parent == "/" ? "/camera_info" : parent + "/camera_info";
  }

  void wake()
  {
    {
      std::lock_guard<std::mutex> lock(wake_mutex_);
      woken_ = true;
    }
    wake_.notify_one();
  }

  /* The mount body -> camera as the transforms say it: fixed on /tf_static alone, or moving. */
  yawdepth::MountLookup mount(const std::string &body, const std::string &camera) const
  {
    yawdepth::MountLookup m;
    if (static_tf_.canTransform(body, camera, ros::Time(0), &m.why))
      m.fixed = toVisp(static_tf_.lookupTransform(body, camera, ros::Time(0)).transform);
    else
      m.moving = tf_.canTransform(body, camera, ros::Time(0));
    return m;
  }

  void pushImage(const ros::Time &stamp, const std::string &frame_id, const cv::Mat &gray)
  {
    if (!node_.started()) {
      const std::string waiting =
          node_.start(frame_id, [this](const std::string &b, const std::string &c) { return mount(b, c); });
      if (!waiting.empty()) {
        ROS_WARN_THROTTLE(5, "yawdepth_node: %s", waiting.c_str());
        return;
      }
      ROS_INFO("yawdepth_node: measuring: mount %s -> %s%s, method %s", node_.bodyFrame().c_str(),
               node_.cameraFrame().c_str(), node_.movingMount() ? " (moving: the camera's pose is the motion)" : "",
               yawdepth::toString(node_.settings().online.method));
      if (node_.movingMount() && !node_.settings().joint.empty()) // the INFO above says it; a set ~joint is unused
        ROS_WARN("yawdepth_node: the camera's mount %s -> %s moves in /tf, which holds the pan: ~joint %s is not used",
                 node_.bodyFrame().c_str(), node_.cameraFrame().c_str(), node_.settings().joint.c_str());
    }
    {
      std::lock_guard<std::mutex> lock(stamps_mutex_);
      stamps_.emplace_back(stamp.toSec(), stamp);
      while (stamps_.size() > 4 * static_cast<std::size_t>(node_.settings().online.max_queued_images) + 8)
        stamps_.pop_front();
    }
    node_.pushImage(stamp.toSec(), gray);
    wake();
  }

  void onImage(const sensor_msgs::ImageConstPtr &msg)
  {
    guarded("image", [&] {
      // 8UC1 is gray already (cv_bridge converts only named colour encodings); the others to mono8.
      cv_bridge::CvImageConstPtr gray = msg->encoding == sensor_msgs::image_encodings::TYPE_8UC1
                                            ? cv_bridge::toCvShare(msg)
                                            : cv_bridge::toCvShare(msg, sensor_msgs::image_encodings::MONO8);
      pushImage(msg->header.stamp, msg->header.frame_id, gray->image);
    });
  }

  void onCompressed(const sensor_msgs::CompressedImageConstPtr &msg)
  {
    guarded("image", [&] {
      const cv::Mat gray = cv::imdecode(msg->data, cv::IMREAD_GRAYSCALE);
      if (gray.empty())
        throw Error(compressed_sub_.getTopic() + ": an image (format '" + msg->format + "') that OpenCV cannot decode");
      pushImage(msg->header.stamp, msg->header.frame_id, gray);
    });
  }

  void onInfo(const sensor_msgs::CameraInfoConstPtr &msg)
  {
    guarded("camera_info", [&] {
      if (!node_.setCameraInfo(toYawdepth(*msg), camera_info_topic_))
        ROS_WARN_ONCE("yawdepth_node: %s changed; the node keeps the first calibration", camera_info_topic_.c_str());
    });
  }

  void onTfStatic(const tf2_msgs::TFMessageConstPtr &msg)
  {
    std::lock_guard<std::mutex> lock(statics_mutex_);
    for (const geometry_msgs::TransformStamped &t : msg->transforms) {
      tf_.setTransform(t, "tf_static", true);
      static_tf_.setTransform(t, "tf_static", true);
      statics_[t.child_frame_id] = t; // one per frame: bounded however often it is published
    }
  }

  /* The transform the node's queued motion waits for (MeasuringNode::queueMotion): the chain world ->
     motion frame (motion: tf) or the moving mount body -> camera (odometry), at the sample's exact
     stamp (its tag, in ns), when the buffer has it. */
  std::optional<vpHomogeneousMatrix> transformAt(std::uint64_t stamp_ns)
  {
    ros::Time stamp;
    stamp.fromNSec(stamp_ns);
    const bool tf_motion = node_.settings().motion == "tf";
    const std::string &target = tf_motion ? node_.settings().world_frame : node_.bodyFrame();
    const std::string &source = tf_motion ? node_.motionFrame() : node_.cameraFrame();
    if (!tf_.canTransform(target, source, stamp))
      return std::nullopt; // not every link has a reading around it (yet)
    return toVisp(tf_.lookupTransform(target, source, stamp).transform);
  }
  std::size_t resolveMotion()
  {
    return node_.resolveMotion([this](double, std::uint64_t tag) { return transformAt(tag); });
  }

  /* /tf into the buffer; with `motion: tf`, the stamps of this message's links of the chain world ->
     motion frame queued (a pose at each; another transform's stamp, e.g. a localiser's post-dated
     map -> odom, is not the motion's); the queued motion whose transforms are now known, pushed. */
  void onTf(const tf2_msgs::TFMessageConstPtr &msg)
  {
    guarded("/tf", [&] {
      for (const geometry_msgs::TransformStamped &t : msg->transforms)
        tf_.setTransform(t, "tf", false);
      if (!node_.started())
        return;
      if (node_.settings().motion == "tf") {
        const std::string &world = node_.settings().world_frame;
        std::vector<std::string> chain;
        try {
          tf_._chainAsVector(world, ros::Time(), node_.motionFrame(), ros::Time(), world, chain);
        } catch (const tf2::TransformException &) {
          chain.clear(); // not connected (yet): nothing to queue
        }
        const auto bare = [](const std::string &f) { return !f.empty() && f.front() == '/' ? f.substr(1) : f; };
        const auto in_chain = [&](const std::string &f) { // tf2 keeps frame ids without a leading '/'
          return std::find(chain.begin(), chain.end(), bare(f)) != chain.end();
        };
        std::vector<ros::Time> stamps; // a link of the chain: both frames on it, its child not the world
        for (const geometry_msgs::TransformStamped &t : msg->transforms)
          if (in_chain(t.child_frame_id) && in_chain(t.header.frame_id) && bare(t.child_frame_id) != bare(world))
            stamps.push_back(t.header.stamp);
        std::sort(stamps.begin(), stamps.end());
        stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
        for (const ros::Time &s : stamps)
          node_.queueMotion(s.toSec(), s.toNSec());
      }
      if (resolveMotion() > 0)
        wake();
    });
  }

  void onOdometry(const nav_msgs::OdometryConstPtr &msg)
  {
    guarded("odom", [&] {
      node_.setOdometryFrames(msg->header.frame_id, msg->child_frame_id, odom_sub_.getTopic());
      geometry_msgs::Transform wTb;
      wTb.translation.x = msg->pose.pose.position.x;
      wTb.translation.y = msg->pose.pose.position.y;
      wTb.translation.z = msg->pose.pose.position.z;
      wTb.rotation = msg->pose.pose.orientation;
      const vpHomogeneousMatrix wMb = toVisp(wTb);
      if (!node_.started())
        return;
      if (node_.movingMount()) { // the pose waits for the mount at its time (its link may come later)
        node_.queueMotion(msg->header.stamp.toSec(), msg->header.stamp.toNSec(), wMb);
        if (resolveMotion() > 0)
          wake();
        return;
      }
      node_.pushMotion(msg->header.stamp.toSec(), wMb);
      wake();
    });
  }

  void onJoints(const sensor_msgs::JointStateConstPtr &msg)
  {
    guarded("joint_states", [&] {
      if (node_.pushJointState(msg->header.stamp.toSec(), msg->name, msg->position, joint_sub_.getTopic()))
        wake();
      else
        ROS_WARN_THROTTLE(10, "yawdepth_node: %s has no joint %s", joint_sub_.getTopic().c_str(),
                          node_.settings().joint.c_str());
    });
  }

  /* Runs a callback's body; an exception is a bad message: logged (throttled), counted, the stream goes on. */
  template <typename F> void guarded(const char *what, F &&body)
  {
    try {
      body();
    } catch (const std::exception &e) {
      ROS_ERROR_THROTTLE(2, "yawdepth_node: %s: %s", what, e.what());
      node_.noteBadMessage();
    }
  }

  ros::Time stampOf(double t)
  {
    std::lock_guard<std::mutex> lock(stamps_mutex_);
    for (const auto &[seconds, stamp] : stamps_)
      if (seconds == t)
        return stamp;
    return ros::Time(t);
  }

  static sensor_msgs::PointCloud2 cloudMessage(const std_msgs::Header &header,
                                               const std::vector<yawdepth::CloudPoint> &cloud, bool world)
  {
    sensor_msgs::PointCloud2 msg;
    msg.header = header;
    sensor_msgs::PointCloud2Modifier modifier(msg);
    modifier.setPointCloud2Fields(6, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32,
                                  "z", 1, sensor_msgs::PointField::FLOAT32, "sigma_z", 1,
                                  sensor_msgs::PointField::FLOAT32, "id", 1, sensor_msgs::PointField::UINT32,
                                  "intensity", 1, sensor_msgs::PointField::FLOAT32);
    modifier.resize(cloud.size());
    msg.height = 1;
    msg.width = static_cast<std::uint32_t>(cloud.size());
    msg.is_dense = true;
    sensor_msgs::PointCloud2Iterator<float> x(msg, "x"), y(msg, "y"), z(msg, "z"), s(msg, "sigma_z"), in(msg, "intensity");
    sensor_msgs::PointCloud2Iterator<std::uint32_t> id(msg, "id");
    for (const yawdepth::CloudPoint &p : cloud) {
      const Eigen::Vector3d &P = world ? p.w_P : p.c_P;
      *x = float(P.x());
      *y = float(P.y());
      *z = float(P.z());
      *s = float(p.sigma_z);
      *id = static_cast<std::uint32_t>(p.id);
      *in = p.intensity;
      ++x, ++y, ++z, ++s, ++id, ++in;
    }
    return msg;
  }

  void publish(const yawdepth::OnlineFrame &f)
  {
    const std::vector<yawdepth::CloudPoint> cloud = node_.cloud(f);
    std_msgs::Header world, camera;
    world.stamp = camera.stamp = stampOf(f.t);
    world.frame_id = node_.worldFrame();
    camera.frame_id = node_.cameraFrame();
    points_pub_.publish(cloudMessage(world, cloud, true));
    points_camera_pub_.publish(cloudMessage(camera, cloud, false));
    if (ros_.publish_markers && markers_pub_.getNumSubscribers() > 0) {
      visualization_msgs::MarkerArray markers;
      visualization_msgs::Marker m;
      m.header = world;
      m.ns = "depth_interval";
      m.id = 0;
      m.type = visualization_msgs::Marker::LINE_LIST;
      m.action = cloud.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
      m.pose.orientation.w = 1;
      m.scale.x = 0.002;
      m.color.g = 0.8f;
      m.color.b = 1.0f;
      m.color.a = 0.8f;
      for (const yawdepth::CloudPoint &p : cloud)
        for (const Eigen::Vector3d *e : {&p.w_near, &p.w_far}) {
          geometry_msgs::Point q;
          q.x = e->x(), q.y = e->y(), q.z = e->z();
          m.points.push_back(q);
        }
      markers.markers.push_back(m);
      markers_pub_.publish(markers);
    }
    if (tracks_pub_.getNumSubscribers() > 0)
      tracks_pub_.publish(cv_bridge::CvImage(camera, sensor_msgs::image_encodings::BGR8, yawdepth::drawTracks(f)).toImageMsg());
  }

  void publishDiagnostics()
  {
    const yawdepth::NodeDiagnostics d = node_.diagnostics();
    diagnostic_msgs::DiagnosticStatus s;
    s.name = ros::this_node::getName() + ": measurer";
    s.hardware_id = node_.started() ? node_.cameraFrame() : std::string("camera");
    s.level = d.warn ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK;
    s.message = d.message;
    for (const auto &[key, value] : d.values) {
      diagnostic_msgs::KeyValue kv;
      kv.key = key;
      kv.value = value;
      s.values.push_back(kv);
    }
    if (d.warn && d.message.rfind("the body turns", 0) == 0)
      ROS_WARN_ONCE("yawdepth_node: %s", d.message.c_str());
    diagnostic_msgs::DiagnosticArray a;
    a.header.stamp = ros::Time::now();
    a.status.push_back(s);
    diagnostics_pub_.publish(a);
  }

  /* ~depths: one control period of a servo client (MeasuringNode::depths). */
  bool onDepths(yawdepth::FeatureDepths::Request &req, yawdepth::FeatureDepths::Response &res)
  {
    yawdepth::ServoDepthRequest r;
    r.t = req.header.stamp.toSec();
    r.ids.assign(req.ids.begin(), req.ids.end());
    r.u = req.u;
    r.v = req.v;
    const yawdepth::ServoDepthAnswer a = node_.depths(r);
    res.error = a.error;
    for (const yawdepth::FeatureDepth &d : a.depths) {
      res.depth.push_back(d.depth);
      res.sigma.push_back(d.sigma);
      res.status.push_back(yawdepth::toString(d.status));
      res.converged.push_back(d.converged);
    }
    return true;
  }

  ros::NodeHandle nh_, pnh_;
  yawdepth::MeasuringNode node_;
  RosParams ros_;
  image_transport::ImageTransport it_;
  image_transport::Subscriber image_sub_;
  image_transport::Publisher tracks_pub_;
  ros::Subscriber compressed_sub_, info_sub_, tf_sub_, tf_static_sub_, odom_sub_, joint_sub_;
  ros::Publisher points_pub_, points_camera_pub_, markers_pub_, diagnostics_pub_;
  ros::CallbackQueue service_queue_;
  ros::ServiceServer depths_srv_;
  std::string camera_info_topic_;
  tf2_ros::Buffer tf_{ros::Duration(30.0)};        // /tf and /tf_static: the motion
  tf2::BufferCore static_tf_{ros::Duration(10.0)}; // /tf_static alone: whether the mount is fixed
  std::mutex statics_mutex_;
  std::map<std::string, geometry_msgs::TransformStamped> statics_; // /tf_static by child frame: kept over a restart

  std::mutex stamps_mutex_; // the images' stamps as received, by their seconds
  std::deque<std::pair<double, ros::Time>> stamps_;

  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool woken_ = false;
  ros::Time last_now_; // the consumer's last look at the (possibly simulated) clock
};

} // namespace

int main(int argc, char **argv)
{
  ros::init(argc, argv, "yawdepth_node");
  try {
    cv::setNumThreads(1);
    YawdepthNode node;
    ros::AsyncSpinner spinner(3);
    ros::AsyncSpinner service_spinner(1, &node.serviceQueue());
    spinner.start();
    service_spinner.start();
    node.run();
    service_spinner.stop();
    spinner.stop();
  } catch (const std::exception &e) {
    std::fprintf(stderr, "yawdepth_node: %s\n", e.what()); // one line, whether or not rosconsole is up
    return 1;
  }
  return 0;
}
