/*
  yawdepth_node: the ROS 1 adapter over yawdepth::OnlineMeasurer (issue 37; docs/ros.md gives the
  topics, parameters and frames). No logic of its own: messages in are converted and pushed,
  measured frames out are converted and published; the library owns the timing rules
  (interpolation, no extrapolation, bounds), the cloud, the counts and the drawing.

  Frames: w the world (`~world_frame`, or the odometry's header.frame_id), b the body
  (`~body_frame`, or the odometry's child_frame_id), v the vision frame (b itself, or with a pan
  joint panJointFrame(~joint_axis, ~joint_origin): bMv), c the camera (`~camera_frame`, default the
  images' frame_id; an optical frame). wMb comes from TF or the odometry, bMc (the mount at pan 0)
  from /tf_static, the rig's vMc(0) = bMv^-1 bMc.

  Threads: the callbacks run on an AsyncSpinner and only push (non-blocking); the main thread waits
  for pushes, calls OnlineMeasurer::process() and publishes.
*/
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <deque>
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
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <visualization_msgs/MarkerArray.h>
#include <visp3/core/vpQuaternionVector.h>
#include <visp3/core/vpTranslationVector.h>

#include <yawdepth/FeatureDepths.h> // generated from srv/FeatureDepths.srv
#include <yawdepth/bag/messages.h>
#include <yawdepth/error.h>
#include <yawdepth/online/frame_outputs.h>
#include <yawdepth/online/online_measurer.h>
#include <yawdepth/servo/depth_provider.h>

namespace {

using yawdepth::Error;

/* The node's parameters (docs/ros.md, "Parameters"); the defaults of the measurer's options are
   the library's own (OnlineOptions, KltOptions, NoiseModel). */
struct NodeConfig {
  std::string motion = "tf";          // tf | odom
  std::string world_frame = "odom";   // tf: the world frame
  std::string body_frame = "base_link"; // tf: the body frame
  std::string camera_frame;           // empty: the images' frame_id
  std::string joint;                  // the pan joint's name in joint_states; empty: no pan joint
  Eigen::Vector3d joint_axis{0, 1, 0};
  Eigen::Vector3d joint_origin{0, 0, 0};
  double camera_latency = 0.0;        // s: an image's stamp is this long after its exposure
  std::string image_transport = "raw";
  double interval_sigmas = 2.0;
  bool publish_markers = true;
  double diagnostics_period = 1.0;    // s (wall)
  double service_wait = 0.2;          // s (wall): how long ~depths waits for the motion around its stamp
  yawdepth::OnlineOptions online;
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

NodeConfig readConfig(const ros::NodeHandle &pnh)
{
  NodeConfig c;
  c.motion = param(pnh, "motion", c.motion);
  if (c.motion != "tf" && c.motion != "odom")
    throw Error("~motion: '" + c.motion + "' (tf or odom)");
  c.world_frame = param(pnh, "world_frame", c.world_frame);
  c.body_frame = param(pnh, "body_frame", c.body_frame);
  if (c.motion == "tf" && (c.world_frame.empty() || c.body_frame.empty() || c.world_frame == c.body_frame))
    throw Error("~world_frame, ~body_frame: two different frames are needed with ~motion tf");
  c.camera_frame = param(pnh, "camera_frame", c.camera_frame);
  c.joint = param(pnh, "joint", c.joint);
  c.joint_axis = vectorParam(pnh, "joint_axis", c.joint_axis);
  c.joint_origin = vectorParam(pnh, "joint_origin", c.joint_origin);
  yawdepth::panJointFrame(c.joint_axis, c.joint_origin); // validates: throws for a zero axis
  c.camera_latency = param(pnh, "camera_latency", c.camera_latency);
  if (!std::isfinite(c.camera_latency))
    throw Error("~camera_latency: must be finite");
  c.image_transport = param(pnh, "image_transport", c.image_transport);
  c.interval_sigmas = param(pnh, "interval_sigmas", c.interval_sigmas);
  if (!std::isfinite(c.interval_sigmas) || c.interval_sigmas < 0)
    throw Error("~interval_sigmas: must be finite and not negative");
  c.publish_markers = param(pnh, "publish_markers", c.publish_markers);
  c.diagnostics_period = param(pnh, "diagnostics_period", c.diagnostics_period);
  if (!std::isfinite(c.diagnostics_period) || !(c.diagnostics_period > 0))
    throw Error("~diagnostics_period: must be positive");
  c.service_wait = param(pnh, "service_wait", c.service_wait);
  if (!std::isfinite(c.service_wait) || c.service_wait < 0)
    throw Error("~service_wait: must be finite and not negative");

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
  o.time_offset = -c.camera_latency; // the image at stamp t was taken at t - latency on the motion clock
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
  o.klt.sigma_px = o.noise.sigma_px; // one noise model: the tracker's gate too (as OnlineMeasurer's own)
  try {
    o.validate();
  } catch (const Error &e) {
    throw Error(std::string("parameters: ") + e.what());
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
  YawdepthNode() : pnh_("~"), config_(readConfig(pnh_)), it_(nh_)
  {
    // Inputs.
    std::string image_topic = nh_.resolveName("image");
    // `image:=/camera/image_raw/compressed` names the transport's topic: the image topic is its parent.
    if (config_.image_transport == "compressed" && image_topic.size() > 11 &&
        image_topic.compare(image_topic.size() - 11, 11, "/compressed") == 0)
      image_topic = ros::names::parentNamespace(image_topic);
    if (config_.image_transport == "compressed") {
      // Debian ships no image_transport plugin for compressed images: the CompressedImage topic read
      // directly, decoded by OpenCV (what the plugin does).
      compressed_sub_ = nh_.subscribe(image_topic + "/compressed", 5, &YawdepthNode::onCompressed, this,
                                      ros::TransportHints().tcpNoDelay());
    } else if (config_.image_transport == "raw") {
      image_sub_ = it_.subscribe(image_topic, 5, &YawdepthNode::onImage, this);
    } else {
      throw Error("~image_transport: '" + config_.image_transport + "' (raw or compressed)");
    }
    camera_info_topic_ = param(pnh_, "camera_info_topic", std::string());
    if (camera_info_topic_.empty())
      camera_info_topic_ = siblingInfo(image_topic);
    info_sub_ = nh_.subscribe(camera_info_topic_, 2, &YawdepthNode::onInfo, this);
    tf_static_sub_ = nh_.subscribe("/tf_static", 20, &YawdepthNode::onTfStatic, this);
    if (config_.motion == "tf")
      tf_sub_ = nh_.subscribe("/tf", 200, &YawdepthNode::onTf, this, ros::TransportHints().tcpNoDelay());
    else
      odom_sub_ = nh_.subscribe("odom", 200, &YawdepthNode::onOdometry, this, ros::TransportHints().tcpNoDelay());
    if (!config_.joint.empty())
      joint_sub_ = nh_.subscribe("joint_states", 200, &YawdepthNode::onJoints, this, ros::TransportHints().tcpNoDelay());
    // Outputs.
    // Queues of a second of images: a subscriber catching up after a burst loses no cloud.
    points_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("points", 30);
    points_camera_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("points_camera", 30);
    if (config_.publish_markers)
      markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 5);
    tracks_pub_ = it_.advertise(pnh_.resolveName("tracks"), 2);
    diagnostics_pub_ = nh_.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 5);
    depths_srv_ = pnh_.advertiseService("depths", &YawdepthNode::onDepths, this);
    ROS_INFO("yawdepth_node: images %s (%s), %s, motion from %s%s", image_topic.c_str(), config_.image_transport.c_str(),
             camera_info_topic_.c_str(),
             config_.motion == "tf" ? ("TF " + config_.world_frame + " -> " + config_.body_frame).c_str()
                                    : nh_.resolveName("odom").c_str(),
             config_.joint.empty() ? "" : (", pan joint " + config_.joint + " from " + nh_.resolveName("joint_states")).c_str());
  }

  /* The consumer: process() whenever a push wakes it, publish what it measured, diagnostics. */
  void run()
  {
    ros::WallTime next_diagnostics = ros::WallTime::now() + ros::WallDuration(config_.diagnostics_period);
    while (ros::ok()) {
      {
        std::unique_lock<std::mutex> lock(wake_mutex_);
        wake_.wait_for(lock, std::chrono::milliseconds(50), [this] { return woken_; });
        woken_ = false;
      }
      if (std::shared_ptr<yawdepth::OnlineMeasurer> m = measurer()) {
        for (const yawdepth::OnlineFrame &f : m->process())
          publish(f);
      }
      if (ros::WallTime::now() >= next_diagnostics) {
        publishDiagnostics();
        next_diagnostics = ros::WallTime::now() + ros::WallDuration(config_.diagnostics_period);
      }
    }
  }

private:
  static std::string siblingInfo(const std::string &image_topic)
  {
    const std::string parent = ros::names::parentNamespace(image_topic);
    return parent == "/" ? "/camera_info" : parent + "/camera_info";
  }

  std::shared_ptr<yawdepth::OnlineMeasurer> measurer() const
  {
    std::lock_guard<std::mutex> lock(init_mutex_);
    return measurer_;
  }

  void wake()
  {
    {
      std::lock_guard<std::mutex> lock(wake_mutex_);
      woken_ = true;
    }
    wake_.notify_one();
  }

  /* The measurer, once the camera (camera_info), the camera frame (the first image) and the mount
     (/tf_static: body -> camera) are known. */
  std::shared_ptr<yawdepth::OnlineMeasurer> ready(const std::string &image_frame)
  {
    std::lock_guard<std::mutex> lock(init_mutex_);
    if (measurer_)
      return measurer_;
    if (!info_) {
      ROS_WARN_THROTTLE(5, "yawdepth_node: waiting for %s", camera_info_topic_.c_str());
      return nullptr;
    }
    const std::string camera_frame = config_.camera_frame.empty() ? image_frame : config_.camera_frame;
    if (camera_frame.empty())
      throw Error(nh_.resolveName("image") + ": the images have no frame_id: set ~camera_frame");
    const std::string body = config_.motion == "tf" ? config_.body_frame : odom_body_;
    if (body.empty()) {
      ROS_WARN_THROTTLE(5, "yawdepth_node: waiting for %s (its child_frame_id is the body)", nh_.resolveName("odom").c_str());
      return nullptr;
    }
    // The mount: fixed on /tf_static; or moving on /tf (a pan joint published by robot_state_publisher),
    // when the camera's own pose is the motion (as import-bag does).
    vpHomogeneousMatrix bMc;
    bool moving = false;
    if (body != camera_frame) {
      std::string why;
      if (static_tf_.canTransform(body, camera_frame, ros::Time(0), &why)) {
        bMc = toVisp(static_tf_.lookupTransform(body, camera_frame, ros::Time(0)).transform);
      } else if (tf_.canTransform(body, camera_frame, ros::Time(0))) {
        moving = true;
        ROS_WARN("yawdepth_node: the camera's mount %s -> %s moves in /tf: the camera's own pose is the motion%s",
                 body.c_str(), camera_frame.c_str(), config_.joint.empty() ? "" : " (~joint is not used)");
      } else {
        ROS_WARN_THROTTLE(5, "yawdepth_node: waiting for the camera mount %s -> %s on /tf_static (%s)", body.c_str(),
                          camera_frame.c_str(), why.c_str());
        return nullptr;
      }
    }
    moving_mount_ = moving;
    bMv_ = config_.joint.empty() || moving ? vpHomogeneousMatrix()
                                           : yawdepth::panJointFrame(config_.joint_axis, config_.joint_origin);
    const yawdepth::YawRig rig = moving ? yawdepth::YawRig() : yawdepth::YawRig(bMv_.inverse() * bMc);
    const yawdepth::CameraModel camera = yawdepth::cameraFromCameraInfo(*info_, camera_info_topic_);
    rig_ = std::make_unique<yawdepth::YawRig>(rig);
    camera_frame_ = camera_frame;
    measurer_ = std::make_shared<yawdepth::OnlineMeasurer>(camera, rig, config_.online);
    yawdepth::DepthProviderOptions po;
    po.method = config_.online.method;
    po.noise = config_.online.noise;
    po.window = config_.online.window;
    po.validate();
    provider_ = std::make_unique<yawdepth::DepthProvider>(camera, rig, po);
    ROS_INFO("yawdepth_node: measuring: camera %ux%u, mount %s -> %s, method %s", info_->width, info_->height,
             body.c_str(), camera_frame.c_str(), yawdepth::toString(config_.online.method));
    return measurer_;
  }

  void pushImage(const ros::Time &stamp, const std::string &frame_id, const cv::Mat &gray)
  {
    std::shared_ptr<yawdepth::OnlineMeasurer> m = ready(frame_id);
    if (!m)
      return;
    {
      std::lock_guard<std::mutex> lock(stamps_mutex_);
      stamps_.emplace_back(stamp.toSec(), stamp);
      while (stamps_.size() > std::size_t(4 * config_.online.max_queued_images + 8))
        stamps_.pop_front();
    }
    m->pushImage(stamp.toSec(), gray);
    wake();
  }

  void onImage(const sensor_msgs::ImageConstPtr &msg)
  {
    guarded("image", [&] {
      cv_bridge::CvImageConstPtr gray = cv_bridge::toCvShare(msg, sensor_msgs::image_encodings::MONO8);
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
      std::lock_guard<std::mutex> lock(init_mutex_);
      const yawdepth::CameraInfoMessage c = toYawdepth(*msg);
      if (!info_) {
        yawdepth::cameraFromCameraInfo(c, camera_info_topic_); // refuse a bad one now, with its reason
        info_ = c;
      } else if (!yawdepth::sameCalibration(*info_, c)) {
        ROS_WARN_ONCE("yawdepth_node: %s changed; the node keeps the first calibration", camera_info_topic_.c_str());
      }
    });
  }

  void onTfStatic(const tf2_msgs::TFMessageConstPtr &msg)
  {
    for (const geometry_msgs::TransformStamped &t : msg->transforms) {
      tf_.setTransform(t, "tf_static", true);
      static_tf_.setTransform(t, "tf_static", true);
    }
  }

  /* /tf into the buffer; then the chain world -> body at each new stamp of this message where it
     resolves, pushed as a pose. */
  void onTf(const tf2_msgs::TFMessageConstPtr &msg)
  {
    guarded("/tf", [&] {
      std::vector<ros::Time> stamps;
      for (const geometry_msgs::TransformStamped &t : msg->transforms) {
        tf_.setTransform(t, "tf", false);
        stamps.push_back(t.header.stamp);
      }
      std::shared_ptr<yawdepth::OnlineMeasurer> m = measurer();
      if (!m)
        return;
      std::sort(stamps.begin(), stamps.end());
      stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
      // The body's pose (the camera's with a moving mount).
      const std::string &target = moving_mount_ ? camera_frame_ : config_.body_frame;
      for (const ros::Time &s : stamps) {
        if (!tf_.canTransform(config_.world_frame, target, s))
          continue; // not every link of the chain has a reading around it (yet)
        const vpHomogeneousMatrix wMb = toVisp(tf_.lookupTransform(config_.world_frame, target, s).transform);
        m->pushPose(s.toSec(), yawdepth::MotionSample::fromPose(0, wMb * bMv_));
      }
      wake();
    });
  }

  void onOdometry(const nav_msgs::OdometryConstPtr &msg)
  {
    guarded("odom", [&] {
      {
        std::lock_guard<std::mutex> lock(init_mutex_);
        if (odom_body_.empty()) {
          odom_body_ = msg->child_frame_id;
          odom_world_ = msg->header.frame_id;
        } else if (msg->child_frame_id != odom_body_ || msg->header.frame_id != odom_world_) {
          throw Error(odom_sub_.getTopic() + ": the pose of " + msg->child_frame_id + " in " + msg->header.frame_id +
                      ", where the first message gave " + odom_body_ + " in " + odom_world_);
        }
      }
      geometry_msgs::TransformStamped wTb; // into the buffer too: a moving mount is chained onto it
      wTb.header = msg->header;
      wTb.child_frame_id = msg->child_frame_id;
      wTb.transform.translation.x = msg->pose.pose.position.x;
      wTb.transform.translation.y = msg->pose.pose.position.y;
      wTb.transform.translation.z = msg->pose.pose.position.z;
      wTb.transform.rotation = msg->pose.pose.orientation;
      const vpHomogeneousMatrix wMb = toVisp(wTb.transform);
      tf_.setTransform(wTb, "odom", false);
      std::shared_ptr<yawdepth::OnlineMeasurer> m = measurer();
      if (!m)
        return;
      vpHomogeneousMatrix bMc;
      if (moving_mount_) { // the mount at this pose's time, or no pose yet (its readings come later)
        if (!tf_.canTransform(odom_body_, camera_frame_, msg->header.stamp))
          return;
        bMc = toVisp(tf_.lookupTransform(odom_body_, camera_frame_, msg->header.stamp).transform);
      }
      m->pushPose(msg->header.stamp.toSec(), yawdepth::MotionSample::fromPose(0, wMb * bMv_ * bMc));
      wake();
    });
  }

  void onJoints(const sensor_msgs::JointStateConstPtr &msg)
  {
    guarded("joint_states", [&] {
      std::shared_ptr<yawdepth::OnlineMeasurer> m = measurer();
      for (std::size_t i = 0; i < msg->name.size(); ++i) {
        if (msg->name[i] != config_.joint)
          continue;
        if (i >= msg->position.size())
          throw Error(joint_sub_.getTopic() + ": joint " + config_.joint + " has no position");
        if (m && !moving_mount_) // with a moving mount, the pan is in the camera's pose already
          m->pushJoint(msg->header.stamp.toSec(), msg->position[i]);
        wake();
        return;
      }
      ROS_WARN_THROTTLE(10, "yawdepth_node: %s has no joint %s", joint_sub_.getTopic().c_str(), config_.joint.c_str());
    });
  }

  /* Runs a callback's body; a yawdepth::Error is a bad message: logged (throttled), the stream goes on. */
  template <typename F> void guarded(const char *what, F &&body)
  {
    try {
      body();
    } catch (const std::exception &e) {
      ROS_ERROR_THROTTLE(2, "yawdepth_node: %s: %s", what, e.what());
      std::lock_guard<std::mutex> lock(diag_mutex_);
      ++bad_messages_;
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

  sensor_msgs::PointCloud2 cloudMessage(const std_msgs::Header &header, const std::vector<yawdepth::CloudPoint> &cloud,
                                        bool world)
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
    const std::vector<yawdepth::CloudPoint> cloud = yawdepth::frameCloud(f, *rig_, config_.interval_sigmas);
    std_msgs::Header world, camera;
    world.stamp = camera.stamp = stampOf(f.t);
    world.frame_id = config_.motion == "tf" ? config_.world_frame : odom_world_;
    camera.frame_id = camera_frame_;
    points_pub_.publish(cloudMessage(world, cloud, true));
    points_camera_pub_.publish(cloudMessage(camera, cloud, false));
    if (config_.publish_markers && markers_pub_.getNumSubscribers() > 0) {
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
    std::lock_guard<std::mutex> lock(diag_mutex_);
    ++frames_;
    latencies_ms_.push_back(f.latency_ms);
    last_counts_ = yawdepth::countByStatus(f);
    last_cloud_ = cloud.size();
  }

  void publishDiagnostics()
  {
    diagnostic_msgs::DiagnosticStatus s;
    s.name = ros::this_node::getName() + ": measurer";
    s.hardware_id = camera_frame_.empty() ? "camera" : camera_frame_;
    auto add = [&s](const std::string &k, const std::string &v) {
      diagnostic_msgs::KeyValue kv;
      kv.key = k;
      kv.value = v;
      s.values.push_back(kv);
    };
    std::shared_ptr<yawdepth::OnlineMeasurer> m = measurer();
    const ros::WallTime now = ros::WallTime::now();
    std::lock_guard<std::mutex> lock(diag_mutex_);
    const double period = last_diagnostics_.isZero() ? config_.diagnostics_period : (now - last_diagnostics_).toSec();
    last_diagnostics_ = now;
    if (!m) {
      s.level = diagnostic_msgs::DiagnosticStatus::WARN;
      s.message = "waiting for camera_info, the camera mount or the motion";
    } else {
      const yawdepth::OnlineStats st = m->stats();
      const std::size_t dropped = st.dropped_stale + st.dropped_uncovered + st.dropped_overflow;
      const bool dropping = dropped > last_dropped_;
      // The body turning about another axis than the pan's: a wrong ~joint_axis (or mount), which the
      // data reveal (the library's TurnAxis rule, as import-bag's warning).
      std::string off_axis;
      if (st.turns_off_pan_axis) {
        const Eigen::Vector3d v_axis = st.turn_axis.normalized();
        Eigen::Vector3d b_axis;
        for (unsigned i = 0; i < 3; ++i)
          b_axis[i] = bMv_[i][0] * v_axis[0] + bMv_[i][1] * v_axis[1] + bMv_[i][2] * v_axis[2];
        char text[200];
        std::snprintf(text, sizeof text, "the body turns about (%.2f, %.2f, %.2f) in the body frame, not about ~joint_axis",
                      b_axis.x(), b_axis.y(), b_axis.z());
        off_axis = text;
        ROS_WARN_ONCE("yawdepth_node: %s: check ~joint_axis (REP 103's base_link: [0, 0, 1]) and ~joint_origin",
                      off_axis.c_str());
      }
      s.level = dropping || bad_messages_ > 0 || !off_axis.empty() ? diagnostic_msgs::DiagnosticStatus::WARN
                                                                    : diagnostic_msgs::DiagnosticStatus::OK;
      s.message = !off_axis.empty() ? off_axis : dropping ? "images dropped" : bad_messages_ > 0 ? "bad messages" : "measuring";
      last_dropped_ = dropped;
      add("images pushed", std::to_string(st.images_pushed));
      add("images measured", std::to_string(st.images_measured));
      add("measured rate (Hz)", std::to_string(double(frames_) / std::max(period, 1e-9)));
      add("dropped stale", std::to_string(st.dropped_stale));
      add("dropped uncovered", std::to_string(st.dropped_uncovered));
      add("dropped overflow", std::to_string(st.dropped_overflow));
      add("out of order (images, poses, joints)", std::to_string(st.out_of_order_images) + ", " +
                                                      std::to_string(st.out_of_order_poses) + ", " +
                                                      std::to_string(st.out_of_order_joints));
      add("queued images", std::to_string(st.queued_images));
      std::vector<double> l = latencies_ms_;
      std::sort(l.begin(), l.end());
      if (!l.empty()) { // none without an image measured in the period
        add("latency median (ms)", std::to_string(l[l.size() / 2]));
        add("latency max (ms)", std::to_string(l.back()));
      }
      add("points published (last image)", std::to_string(last_cloud_));
      for (const auto &[status, n] : last_counts_)
        add(std::string("points ") + yawdepth::toString(status) + " (last image)", std::to_string(n));
      add("bad messages", std::to_string(bad_messages_));
    }
    frames_ = 0;
    latencies_ms_.clear();
    diagnostic_msgs::DiagnosticArray a;
    a.header.stamp = ros::Time::now();
    a.status.push_back(s);
    diagnostics_pub_.publish(a);
  }

  /* ~depths: one control period of a servo client (DepthProvider). */
  bool onDepths(yawdepth::FeatureDepths::Request &req, yawdepth::FeatureDepths::Response &res)
  {
    try {
      std::shared_ptr<yawdepth::OnlineMeasurer> m = measurer();
      if (!m)
        throw Error("not measuring yet (waiting for camera_info, the camera mount or the motion)");
      if (req.u.size() != req.ids.size() || req.v.size() != req.ids.size())
        throw Error("ids, u and v must have the same length");
      const double t_motion = req.header.stamp.toSec() + config_.online.time_offset;
      yawdepth::MotionSample pose;
      const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(config_.service_wait);
      while (!m->poseAt(t_motion, pose)) {
        if (ros::WallTime::now() >= until || !ros::ok())
          throw Error("no motion around t = " + std::to_string(req.header.stamp.toSec()) +
                      " s (the pose or joint streams do not cover it, within ~service_wait)");
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
      std::vector<std::pair<long, vpImagePoint>> points;
      for (std::size_t i = 0; i < req.ids.size(); ++i)
        points.emplace_back(long(req.ids[i]), vpImagePoint(req.v[i], req.u[i]));
      std::lock_guard<std::mutex> lock(provider_mutex_);
      provider_->update(pose, points);
      for (std::int64_t id : req.ids) {
        const yawdepth::FeatureDepth d = provider_->info(long(id));
        res.depth.push_back(d.depth);
        res.sigma.push_back(d.sigma);
        res.status.push_back(yawdepth::toString(d.status));
        res.converged.push_back(d.converged);
      }
    } catch (const std::exception &e) {
      res = yawdepth::FeatureDepths::Response();
      res.error = e.what();
    }
    return true;
  }

  ros::NodeHandle nh_, pnh_;
  NodeConfig config_;
  image_transport::ImageTransport it_;
  image_transport::Subscriber image_sub_;
  image_transport::Publisher tracks_pub_;
  ros::Subscriber compressed_sub_, info_sub_, tf_sub_, tf_static_sub_, odom_sub_, joint_sub_;
  ros::Publisher points_pub_, points_camera_pub_, markers_pub_, diagnostics_pub_;
  ros::ServiceServer depths_srv_;
  std::string camera_info_topic_;
  tf2_ros::Buffer tf_{ros::Duration(30.0)};   // /tf, /tf_static (and the odometry): the motion
  tf2::BufferCore static_tf_{ros::Duration(10.0)}; // /tf_static alone: whether the mount is fixed

  mutable std::mutex init_mutex_; // the measurer and what it is made of
  std::optional<yawdepth::CameraInfoMessage> info_;
  std::string odom_body_, odom_world_, camera_frame_;
  bool moving_mount_ = false;
  vpHomogeneousMatrix bMv_;
  std::unique_ptr<yawdepth::YawRig> rig_;
  std::shared_ptr<yawdepth::OnlineMeasurer> measurer_;
  std::mutex provider_mutex_;
  std::unique_ptr<yawdepth::DepthProvider> provider_;

  std::mutex stamps_mutex_; // the images' stamps as received, by their seconds
  std::deque<std::pair<double, ros::Time>> stamps_;

  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool woken_ = false;

  std::mutex diag_mutex_;
  std::size_t frames_ = 0, last_dropped_ = 0, last_cloud_ = 0, bad_messages_ = 0;
  std::vector<double> latencies_ms_;
  std::vector<std::pair<yawdepth::Status, std::size_t>> last_counts_;
  ros::WallTime last_diagnostics_;
};

} // namespace

int main(int argc, char **argv)
{
  ros::init(argc, argv, "yawdepth_node");
  try {
    cv::setNumThreads(1);
    YawdepthNode node;
    ros::AsyncSpinner spinner(3);
    spinner.start();
    node.run();
    spinner.stop();
  } catch (const std::exception &e) {
    std::fprintf(stderr, "yawdepth_node: %s\n", e.what()); // one line, whether or not rosconsole is up
    return 1;
  }
  return 0;
}
