// importBag(): a bag turned into images/, motion.csv, camera.yaml and rig.yaml. Pass 1 reads the
// small topics (motion, /tf, /tf_static, joint, camera_info); pass 2 streams the images, each
// written as it comes into a staging folder inside out_dir that is renamed into place at the end.
#include <yawdepth/bag/import.h>

#include "readers.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdlib.h> // mkdtemp
#include <cstring>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpQuaternionVector.h>
#include <visp3/core/vpThetaUVector.h>
#include <yawdepth/bag/bag.h>
#include <yawdepth/bag/messages.h>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/io/recording.h>

#ifdef YAWDEPTH_BAG_TF2
#include <geometry_msgs/TransformStamped.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#endif

namespace yawdepth {

namespace fs = std::filesystem;

namespace {

constexpr const char *kTf = "/tf";
constexpr const char *kTfStatic = "/tf_static";

std::string sec(double s)
{
  char t[64];
  std::snprintf(t, sizeof t, "%.3f", s);
  return t;
}
double toSec(std::int64_t ns) { return double(ns) * 1e-9; }

/* The pose of a position and quaternion; throws for a quaternion that is not one, the message
   starting with `where` (a prefix that ends in ": "). */
vpHomogeneousMatrix poseOf(const std::array<double, 3> &p, const std::array<double, 4> &q, const std::string &where)
{
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double v : p)
    if (!std::isfinite(v))
      throw Error(where + "a position that is not finite");
  if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-3)
    throw Error(where + "a quaternion of norm " + std::to_string(n) + ", not 1");
  return vpHomogeneousMatrix(vpTranslationVector(p[0], p[1], p[2]),
                             vpRotationMatrix(vpQuaternionVector(q[0] / n, q[1] / n, q[2] / n, q[3] / n)));
}

/* The sibling camera_info of an image topic. */
std::string siblingCameraInfo(const std::string &image_topic, bool compressed)
{
  fs::path p(image_topic);
  if (compressed && p.filename() == "compressed")
    p = p.parent_path();
  return (p.parent_path() / "camera_info").generic_string();
}

const BagTopic &requireTopic(const BagReader &bag, const std::string &name, const std::string &option,
                             std::initializer_list<const char *> types)
{
  const BagTopic *t = bag.topic(name);
  if (!t)
    throw Error(bag.path() + ": no topic " + name + " (" + option + "); the bag has: " + bag.topicList());
  std::string names;
  for (const char *ty : types) {
    if (t->type == ty)
      return *t;
    names += (names.empty() ? "" : " or ") + std::string(ty);
  }
  throw Error(bag.path() + ": " + name + " (" + option + ") is " + t->type + ", not " + names);
}

struct Stamped {
  std::int64_t t = 0; // ns
  vpHomogeneousMatrix M;
};

/* The vision frame of a pan joint in the body: +Y along `axis`, the origin at `origin` (the smallest
   rotation taking +Y to the axis). */
Eigen::Matrix3d rotationOf(const vpHomogeneousMatrix &M)
{
  Eigen::Matrix3d R;
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j)
      R(i, j) = M[i][j];
  return R;
}

/* Linear interpolation of a sorted (stamp, value) series; -1 before, 1 after, 2 in a gap, 0 ok. */
int interpolate(const std::vector<std::pair<double, double>> &s, double t, double gap, double &value)
{
  if (s.empty() || t < s.front().first)
    return -1;
  if (t > s.back().first)
    return 1;
  auto it = std::lower_bound(s.begin(), s.end(), t, [](const auto &a, double x) { return a.first < x; });
  if (it->first == t) {
    value = it->second;
    return 0;
  }
  const auto &b = *it, &a = *(it - 1);
  if (b.first - a.first > gap)
    return 2;
  const double f = (t - a.first) / (b.first - a.first);
  value = a.second + f * (b.second - a.second);
  return 0;
}

/* A folder removed on destruction unless released. */
struct TempDir {
  fs::path path;
  bool keep = false;
  ~TempDir()
  {
    if (!keep && !path.empty()) {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  }
};


#ifdef YAWDEPTH_BAG_TF2
geometry_msgs::TransformStamped toRos(const TransformMessage &t)
{
  geometry_msgs::TransformStamped r;
  r.header.frame_id = t.header.frame_id;
  r.header.stamp.fromNSec(std::uint64_t(std::max<std::int64_t>(t.header.stamp, 0)));
  r.child_frame_id = t.child_frame_id;
  r.transform.translation.x = t.translation[0];
  r.transform.translation.y = t.translation[1];
  r.transform.translation.z = t.translation[2];
  r.transform.rotation.x = t.rotation[0];
  r.transform.rotation.y = t.rotation[1];
  r.transform.rotation.z = t.rotation[2];
  r.transform.rotation.w = t.rotation[3];
  return r;
}

vpHomogeneousMatrix fromRos(const geometry_msgs::TransformStamped &t, const std::string &what)
{
  const auto &tr = t.transform.translation;
  const auto &q = t.transform.rotation;
  return poseOf({tr.x, tr.y, tr.z}, {q.x, q.y, q.z, q.w}, what + ": ");
}

std::string framesOf(const tf2::BufferCore &buffer)
{
  std::vector<std::string> ids;
  buffer._getFrameStrings(ids);
  std::sort(ids.begin(), ids.end());
  std::string s;
  for (const std::string &f : ids)
    s += (s.empty() ? "" : ", ") + f;
  return s.empty() ? std::string("none") : s;
}
#endif

/* An image message as an OpenCV image to write (raw) or the bytes as they are (compressed). */
struct DecodedImage {
  cv::Mat mat;                      // raw: what imwrite writes
  std::vector<std::uint8_t> bytes;  // compressed: written as they are
  std::string ext;                  // ".png" or ".jpg"
  std::int64_t stamp = 0;
  std::string frame_id;
  int width = 0, height = 0;
};

DecodedImage decodeRaw(const BagMessage &m)
{
  ImageMessage im = decodeImage(m);
  DecodedImage d;
  d.stamp = im.header.stamp;
  d.frame_id = im.header.frame_id;
  d.width = int(im.width);
  d.height = int(im.height);
  d.ext = ".png";
  const std::string &e = im.encoding;
  int type = -1, bytes_per_pixel = 0;
  if (e == "mono8" || e == "8UC1")
    type = CV_8UC1, bytes_per_pixel = 1;
  else if (e == "rgb8" || e == "bgr8" || e == "8UC3")
    type = CV_8UC3, bytes_per_pixel = 3;
  else if (e == "mono16" || e == "16UC1")
    type = CV_16UC1, bytes_per_pixel = 2;
  else
    throw Error(m.topic->name + ": image encoding '" + e +
                "' (import-bag reads mono8, rgb8, bgr8, mono16 and CompressedImage jpeg or png)");
  if (im.width == 0 || im.height == 0 || im.width > 65535 || im.height > 65535)
    throw Error(bag_detail::messageWhere(m) + "an image of " +
                std::to_string(im.width) + " x " + std::to_string(im.height) + " pixels");
  if (std::uint64_t(im.step) < std::uint64_t(im.width) * bytes_per_pixel ||
      std::uint64_t(im.step) * im.height > im.data.size())
    throw Error(bag_detail::messageWhere(m) + std::to_string(im.data.size()) +
                " bytes of data for " + std::to_string(im.height) + " rows of " + std::to_string(im.step) +
                " bytes (step) and " + std::to_string(im.width) + " " + e + " pixels");
  cv::Mat view(int(im.height), int(im.width), type, im.data.data(), im.step);
  if (e == "rgb8")
    cv::cvtColor(view, d.mat, cv::COLOR_RGB2BGR);
  else
    d.mat = view.clone();
  if (type == CV_16UC1 && im.is_bigendian)
    for (int r = 0; r < d.mat.rows; ++r)
      for (int c = 0; c < d.mat.cols; ++c) {
        std::uint16_t &v = d.mat.at<std::uint16_t>(r, c);
        v = std::uint16_t((v >> 8) | (v << 8));
      }
  return d;
}

DecodedImage decodeCompressed(const BagMessage &m)
{
  CompressedImageMessage cm = decodeCompressedImage(m);
  DecodedImage d;
  d.stamp = cm.header.stamp;
  d.frame_id = cm.header.frame_id;
  const std::vector<std::uint8_t> &b = cm.data;
  const std::string where = bag_detail::messageWhere(m);
  if (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G')
    d.ext = ".png";
  else if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF)
    d.ext = ".jpg";
  else
    throw Error(where + "format '" + cm.format + "': neither a JPEG nor a PNG by its first bytes");
  cv::Mat img;
  try {
    img = cv::imdecode(cv::Mat(1, int(b.size()), CV_8UC1, const_cast<std::uint8_t *>(b.data())), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception &e) {
    throw Error(where + "cannot decode the " + d.ext.substr(1) + " image (" + e.err + ")");
  }
  if (img.empty())
    throw Error(where + "cannot decode the " + d.ext.substr(1) + " image (truncated or damaged)");
  d.width = img.cols;
  d.height = img.rows;
  d.bytes = std::move(cm.data);
  return d;
}

} // namespace

void BagImportOptions::validate() const
{
  if (bag.empty())
    throw Error("import-bag: no bag given");
  if (out_dir.empty())
    throw Error("--out-dir: empty folder name");
  if (image_topic.empty())
    throw Error("--image-topic is required");
  const bool tf = !tf_world.empty() || !tf_body.empty();
  const int sources = int(!odom_topic.empty()) + int(!pose_topic.empty()) + int(tf);
  if (sources == 0)
    throw Error("give the motion: one of --odom-topic, --pose-topic or --tf WORLD:BODY");
  if (sources > 1) {
    std::string given;
    for (const auto &[set, name] : {std::pair<bool, const char *>{!odom_topic.empty(), "--odom-topic"},
                                    {!pose_topic.empty(), "--pose-topic"}, {tf, "--tf"}})
      if (set)
        given += (given.empty() ? "" : " and ") + std::string(name);
    throw Error("give one motion source, not " + given);
  }
  if (tf && (tf_world.empty() || tf_body.empty()))
    throw Error("--tf " + tf_world + ":" + tf_body + ": give WORLD:BODY, two frame names");
  if (tf && tf_world == tf_body)
    throw Error("--tf " + tf_world + ":" + tf_body + ": WORLD and BODY are the same frame");
  if (joint_topic.empty() != joint.empty())
    throw Error(joint_topic.empty() ? "--joint " + joint + " needs --joint-topic" : "--joint-topic " + joint_topic + " needs --joint NAME");
  if (!std::isfinite(start) || start < 0)
    throw Error("--start " + std::to_string(start) + ": a time in seconds, 0 or more");
  if (!std::isfinite(duration))
    throw Error("--duration: not a finite number");
  if (every < 1)
    throw Error("--every " + std::to_string(every) + ": 1 or more");
  const double axis_norm = std::hypot(joint_axis[0], joint_axis[1], joint_axis[2]);
  if (!std::isfinite(axis_norm) || !(axis_norm > 1e-9))
    throw Error("--joint-axis: three finite numbers, not all 0");
  for (double v : joint_origin)
    if (!std::isfinite(v))
      throw Error("--joint-origin: three finite numbers (m)");
  TimeAlignmentOptions a;
  a.time_offset = time_offset;
  a.max_pose_gap = max_pose_gap;
  a.validate();
}

std::string BagImportResult::summary() const
{
  std::string s = "topics used:";
  for (std::size_t i = 0; i < topics_used.size(); ++i)
    s += (i ? "; " : " ") + topics_used[i];
  s += "\nimages: " + std::to_string(images_read) + " read, stamps over [" + sec(image_first) + ", " +
       sec(image_last) + "] s, " + std::to_string(images_kept) + " kept, " + std::to_string(images_matched) +
       " matched; skipped: " + std::to_string(skipped_before) + " before the motion, " +
       std::to_string(skipped_after) + " after it, " + std::to_string(skipped_gap) + " in its gaps\n";
  s += "motion: " + std::to_string(poses) + " poses over [" + sec(motion_first) + ", " + sec(motion_last) + "] s";
  if (joint_readings > 0)
    s += "; joint: " + std::to_string(joint_readings) + " readings";
  s += "\nwrote: " + images_dir + " (" + std::to_string(images_matched) + " images), " + motion_path + ", " +
       camera_path + ", " + rig_path + "\n";
  return s;
}

BagImportResult importBag(const BagImportOptions &o)
{
  o.validate();
  std::unique_ptr<BagReader> bag = openBag(o.bag);
  const std::string &path = bag->path();

  // The topics, named and typed, before anything is read.
  const BagTopic &image_topic =
      requireTopic(*bag, o.image_topic, "--image-topic", {"sensor_msgs/Image", "sensor_msgs/CompressedImage"});
  const bool compressed = image_topic.type == "sensor_msgs/CompressedImage";
  const std::string info_name =
      o.camera_info_topic.empty() ? siblingCameraInfo(o.image_topic, compressed) : o.camera_info_topic;
  const BagTopic &info_topic = requireTopic(*bag, info_name,
                                            o.camera_info_topic.empty() ? "the image topic's camera_info; give --camera-info-topic"
                                                                        : "--camera-info-topic",
                                            {"sensor_msgs/CameraInfo"});
  const bool tf_motion = !o.tf_world.empty();
  const BagTopic *motion_topic = nullptr;
  std::string motion_name;
  if (!o.odom_topic.empty())
    motion_topic = &requireTopic(*bag, o.odom_topic, "--odom-topic", {"nav_msgs/Odometry"});
  else if (!o.pose_topic.empty())
    motion_topic = &requireTopic(*bag, o.pose_topic, "--pose-topic",
                                 {"geometry_msgs/PoseStamped", "geometry_msgs/PoseWithCovarianceStamped"});
  else
    requireTopic(*bag, kTf, "--tf " + o.tf_world + ":" + o.tf_body, {"tf2_msgs/TFMessage"});
  motion_name = motion_topic ? motion_topic->name : std::string(kTf);
  const BagTopic *joint_topic =
      o.joint_topic.empty() ? nullptr : &requireTopic(*bag, o.joint_topic, "--joint-topic", {"sensor_msgs/JointState"});
  const BagTopic *static_topic = bag->topic(kTfStatic);
  if (static_topic && static_topic->type != "tf2_msgs/TFMessage")
    throw Error(path + ": " + kTfStatic + " is " + static_topic->type + ", not tf2_msgs/TFMessage");
  // /tf is read with any motion source: it may hold a moving mount (a pan joint's link).
  const BagTopic *tf_topic = bag->topic(kTf);
  const bool read_tf = tf_motion || (tf_topic && tf_topic->type == "tf2_msgs/TFMessage");
#ifndef YAWDEPTH_BAG_TF2
  if (tf_motion)
    throw Error("--tf: this build was made without tf2 (Debian: libtf2-dev)");
#endif

  // The window, in log time from the bag's first message.
  std::int64_t first = INT64_MIN;
  bag->read({}, [&](const BagMessage &m) {
    first = m.log_time;
    return false;
  });
  if (first == INT64_MIN)
    throw Error(path + ": no messages");
  const std::int64_t w_start = first + std::int64_t(std::llround(o.start * 1e9));
  const std::int64_t w_end =
      o.duration < 0 ? INT64_MAX : w_start + std::int64_t(std::llround(std::min(o.duration, 1e9) * 1e9));
  // The small topics with a margin, so that the images at the window's edges have poses around them.
  const std::int64_t margin = std::int64_t(std::llround((2.0 + o.max_pose_gap + std::abs(o.time_offset)) * 1e9));
  const std::int64_t s_start = w_start - margin;
  const std::int64_t s_end = w_end == INT64_MAX ? INT64_MAX : w_end + margin;

  // The first image (its frame_id names the camera frame unless --camera-frame does).
  std::string image_frame;
  bool any_image = false;
  {
    BagReadOptions ro;
    ro.topics = {image_topic.name};
    ro.start = w_start;
    ro.end = w_end;
    bag->read(ro, [&](const BagMessage &m) {
      any_image = true;
      image_frame = compressed ? decodeCompressedImage(m).header.frame_id : decodeImage(m).header.frame_id;
      return false;
    });
  }
  if (!any_image)
    throw Error(path + ": " + image_topic.name + " has no message in the window (--start " + std::to_string(o.start) +
                " s" + (o.duration >= 0 ? ", --duration " + std::to_string(o.duration) + " s" : std::string()) + ")");

  // Pass 1: the small topics.
  BagImportResult r;
  std::map<std::string, std::size_t> counts;
  std::vector<Stamped> motion;
  std::string world_frame, body_frame;
  std::vector<std::pair<double, double>> joint;
  bool joint_seen = false;
  std::set<std::string> joint_names;
  std::optional<CameraInfoMessage> info;
  bool info_changed = false;
  std::int64_t info_changed_at = 0;
  std::vector<TransformMessage> statics, dynamics;
  if (static_topic) { // the whole bag's: a latched /tf_static is usually recorded once, at the start
    BagReadOptions ro;
    ro.topics = {kTfStatic};
    bag->read(ro, [&](const BagMessage &m) {
      for (TransformMessage &x : decodeTf(m).transforms)
        statics.push_back(std::move(x));
      ++counts[kTfStatic];
      return true;
    });
  }
  {
    BagReadOptions ro;
    ro.topics = {info_topic.name};
    if (motion_topic)
      ro.topics.push_back(motion_topic->name);
    if (read_tf)
      ro.topics.emplace_back(kTf);
    if (joint_topic)
      ro.topics.push_back(joint_topic->name);
    ro.start = s_start;
    ro.end = s_end;
    bag->read(ro, [&](const BagMessage &m) {
      const std::string &t = m.topic->name;
      const bool in_window = m.log_time >= w_start && m.log_time <= w_end;
      if (t == info_topic.name) {
        if (!in_window && info)
          return true;
        CameraInfoMessage ci = decodeCameraInfo(m);
        ++counts[t];
        if (!info)
          info = std::move(ci);
        else if (!info_changed && !sameCalibration(*info, ci)) {
          info_changed = true;
          info_changed_at = m.log_time;
        }
        return true;
      }
      ++counts[t];
      if (motion_topic && t == motion_topic->name) {
        Stamped s;
        std::string frame, child;
        if (m.topic->type == "nav_msgs/Odometry") {
          const OdometryMessage od = decodeOdometry(m);
          s.t = od.header.stamp;
          s.M = poseOf(od.pose.position, od.pose.orientation, bag_detail::messageWhere(m));
          frame = od.header.frame_id;
          child = od.child_frame_id;
        } else {
          const PoseMessage p = decodePose(m);
          s.t = p.header.stamp;
          s.M = poseOf(p.pose.position, p.pose.orientation, bag_detail::messageWhere(m));
          frame = p.header.frame_id;
        }
        if (motion.empty()) {
          world_frame = frame;
          body_frame = child;
        } else if (frame != world_frame || child != body_frame) {
          throw Error(bag_detail::messageWhere(m) + "the pose of " + (child.empty() ? std::string("?") : child) + " in " +
                      frame + ", where the earlier messages gave " + (body_frame.empty() ? std::string("?") : body_frame) +
                      " in " + world_frame);
        }
        motion.push_back(s);
      } else if (t == kTf) {
        for (TransformMessage &x : decodeTf(m).transforms)
          dynamics.push_back(std::move(x));
      } else if (joint_topic && t == joint_topic->name) {
        const JointStateMessage j = decodeJointState(m);
        for (std::size_t i = 0; i < j.name.size(); ++i) {
          joint_names.insert(j.name[i]);
          if (j.name[i] != o.joint)
            continue;
          if (i >= j.position.size())
            throw Error(bag_detail::messageWhere(m) + "joint " + o.joint + " has no position (" +
                        std::to_string(j.position.size()) + " positions for " + std::to_string(j.name.size()) + " names)");
          if (!std::isfinite(j.position[i]))
            throw Error(bag_detail::messageWhere(m) + "joint " + o.joint + "'s position is not finite");
          joint.emplace_back(toSec(j.header.stamp), j.position[i]);
          joint_seen = true;
        }
      }
      return true;
    });
  }
  if (!info)
    throw Error(path + ": " + info_topic.name + " has no message in the window");
  if (joint_topic && !joint_seen) {
    std::string names;
    for (const std::string &n : joint_names)
      names += (names.empty() ? "" : ", ") + n;
    throw Error(path + ": " + joint_topic->name + " has no joint " + o.joint + " (joints: " +
                (names.empty() ? std::string("none") : names) + ")");
  }
  const CameraModel camera = cameraFromCameraInfo(*info, info_topic.name);
  if (info_changed)
    r.warnings.push_back(info_topic.name + ": camera_info changes during the bag (first at t = " +
                         bag_detail::secondsText(info_changed_at) + " s): camera.yaml is the first one's");
  if (!o.pose_topic.empty() && world_frame.empty())
    world_frame = "?";

  const std::string camera_frame = o.camera_frame.empty() ? image_frame : o.camera_frame;
  if (camera_frame.empty())
    throw Error(image_topic.name + ": the images have no frame_id: give --camera-frame");

  // The motion from /tf, and the camera mount from /tf_static (or, when the mount moves, from /tf at
  // each image's time: `moving`).
  vpHomogeneousMatrix bMc;
  bool moving_mount = false;
#ifdef YAWDEPTH_BAG_TF2
  std::unique_ptr<tf2::BufferCore> moving;
  {
    std::int64_t lo = INT64_MAX, hi = INT64_MIN;
    for (const TransformMessage &t : dynamics) {
      lo = std::min(lo, t.header.stamp);
      hi = std::max(hi, t.header.stamp);
    }
    const double span = hi >= lo ? toSec(hi - lo) : 0.0;
    moving = std::make_unique<tf2::BufferCore>(ros::Duration(std::min(span + 10.0, 4e6)));
    tf2::BufferCore &buffer = *moving;
    tf2::BufferCore static_buffer(ros::Duration(10.0));
    for (const TransformMessage &t : statics) {
      const std::string what = path + ": " + kTfStatic + ": " + t.header.frame_id + " -> " + t.child_frame_id;
      poseOf(t.translation, t.rotation, what + ": "); // refuses a non-unit quaternion, which tf2 would only log
      buffer.setTransform(toRos(t), "bag", true);
      static_buffer.setTransform(toRos(t), "bag", true);
    }
    std::vector<std::int64_t> stamps;
    for (const TransformMessage &t : dynamics) {
      poseOf(t.translation, t.rotation, path + ": /tf: " + t.header.frame_id + " -> " + t.child_frame_id + ": ");
      buffer.setTransform(toRos(t), "bag", false);
      stamps.push_back(t.header.stamp);
    }
    if (tf_motion) {
      world_frame = o.tf_world;
      body_frame = o.tf_body;
      std::string err;
      if (!buffer._frameExists(o.tf_world) || !buffer._frameExists(o.tf_body) ||
          !buffer.canTransform(o.tf_world, o.tf_body, ros::Time(0), &err))
        throw Error(path + ": --tf " + o.tf_world + ":" + o.tf_body + ": no chain from " + o.tf_world + " to " +
                    o.tf_body + " in /tf and /tf_static (frames: " + framesOf(buffer) + ")");
      std::sort(stamps.begin(), stamps.end());
      stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
      for (std::int64_t s : stamps) {
        ros::Time t;
        t.fromNSec(std::uint64_t(std::max<std::int64_t>(s, 0)));
        try {
          Stamped x;
          x.t = s;
          x.M = fromRos(buffer.lookupTransform(o.tf_world, o.tf_body, t), path + ": /tf");
          motion.push_back(x);
        } catch (const tf2::TransformException &) {
          // a stamp before every link of the chain has a reading, or after: no pose there
        }
      }
      if (motion.empty())
        throw Error(path + ": --tf " + o.tf_world + ":" + o.tf_body + ": the chain never has all its links at one time");
    }
    // The body of a pose topic: the root of the camera frame's /tf_static tree (identity when it has none).
    if (!o.pose_topic.empty()) {
      body_frame = camera_frame;
      std::map<std::string, std::string> parent;
      for (const TransformMessage &t : statics)
        parent[t.child_frame_id] = t.header.frame_id;
      for (std::size_t k = 0; k < 64 && parent.count(body_frame); ++k)
        body_frame = parent[body_frame];
    }
    if (body_frame.empty())
      throw Error(motion_name + ": the odometry has no child_frame_id: the body frame is unknown");
    if (body_frame != camera_frame) {
      std::string err;
      if (!static_topic)
        throw Error(path + ": no " + kTfStatic + " topic for the camera's mount " + body_frame + " -> " + camera_frame +
                    "; the bag has: " + bag->topicList());
      if (static_buffer._frameExists(body_frame) && static_buffer._frameExists(camera_frame) &&
          static_buffer.canTransform(body_frame, camera_frame, ros::Time(0), &err)) {
        bMc = fromRos(static_buffer.lookupTransform(body_frame, camera_frame, ros::Time(0)), path + ": /tf_static");
      } else if (!dynamics.empty() && buffer._frameExists(body_frame) && buffer._frameExists(camera_frame) &&
                 buffer.canTransform(body_frame, camera_frame, ros::Time(0), &err)) {
        // The chain passes through /tf's moving links (a pan joint published by robot_state_publisher):
        // the camera's own pose is the motion, bMc looked up at each image's time.
        moving_mount = true;
        if (joint_topic)
          r.warnings.push_back(path + ": the camera's mount " + body_frame + " -> " + camera_frame +
                               " moves in /tf, which holds the pan: " + joint_topic->name + " is not used");
      } else {
        throw Error(path + ": " + kTfStatic + ": no chain from " + body_frame + " to the camera frame " + camera_frame +
                    " (frames: " + framesOf(static_buffer) + "; with /tf: " + framesOf(buffer) + ")");
      }
    }
  }
#else
  if (!o.pose_topic.empty())
    body_frame = camera_frame;
  if (body_frame != camera_frame)
    throw Error(path + ": the camera's mount " + body_frame + " -> " + camera_frame +
                " needs tf2, and this build was made without it (Debian: libtf2-dev)");
#endif
  if (motion.empty())
    throw Error(path + ": " + motion_name + " has no message in the window");
  std::stable_sort(motion.begin(), motion.end(), [](const Stamped &a, const Stamped &b) { return a.t < b.t; });
  motion.erase(std::unique(motion.begin(), motion.end(), [](const Stamped &a, const Stamped &b) { return a.t == b.t; }),
               motion.end());
  const bool use_joint = joint_topic && !moving_mount;
  // With a pan joint, the vision frame on the joint's axis (see BagImportOptions::joint_axis).
  if (use_joint) {
    const vpHomogeneousMatrix bMv = panJointFrame(Eigen::Vector3d(o.joint_axis[0], o.joint_axis[1], o.joint_axis[2]),
                                                  Eigen::Vector3d(o.joint_origin[0], o.joint_origin[1], o.joint_origin[2]));
    for (Stamped &x : motion)
      x.M = x.M * bMv;
    bMc = bMv.inverse() * bMc;
    // A robot that turns about another axis than the pan's (REP 103's z-up base_link with the
    // default +Y): the data reveal it, so say so.
    TurnAxis turn;
    for (const Stamped &x : motion)
      turn.add(rotationOf(x.M));
    if (turn.offPanAxis()) {
      const Eigen::Vector3d &axis = turn.sum();
      const Eigen::Vector3d b = rotationOf(bMv) * axis.normalized();
      char buf[160];
      std::snprintf(buf, sizeof buf, "(%.2f, %.2f, %.2f)", b.x(), b.y(), b.z());
      r.warnings.push_back(path + ": the body turns about " + buf + " in " + body_frame +
                           ", not about the pan axis --joint-axis gives: for REP 103's z-up base_link give "
                           "--joint-axis 0,0,1 and the joint's position as --joint-origin");
    }
  }
  std::sort(joint.begin(), joint.end(), [](const auto &a, const auto &b) { return a.first < b.first; });
  joint.erase(std::unique(joint.begin(), joint.end(), [](const auto &a, const auto &b) { return a.first == b.first; }),
              joint.end());

  // Pass 2: the images, streamed into a staging folder.
  std::error_code ec;
  const bool out_existed = fs::exists(o.out_dir, ec);
  if (out_existed && !fs::is_directory(o.out_dir, ec))
    throw Error("--out-dir " + o.out_dir + ": exists and is not a folder");
  fs::create_directories(o.out_dir, ec);
  if (ec || !fs::is_directory(o.out_dir))
    throw Error("--out-dir " + o.out_dir + ": cannot create the folder" + (ec ? ": " + ec.message() : std::string()));
  struct OutDirGuard { // an out_dir this run created is removed again when it fails
    std::string dir;
    bool created, done = false;
    ~OutDirGuard()
    {
      std::error_code e;
      if (created && !done && fs::is_empty(dir, e))
        fs::remove(dir, e);
    }
  } out_guard{o.out_dir, !out_existed};
  TempDir stage; // created by mkdtemp: unique, never another run's
  {
    std::string templ = (fs::path(o.out_dir) / ".import-bag.XXXXXX").string();
    if (!::mkdtemp(templ.data()))
      throw Error("--out-dir " + o.out_dir + ": cannot create a staging folder in it: " + std::strerror(errno));
    stage.path = templ;
  }
  const fs::path stage_images = stage.path / "images";
  fs::create_directories(stage_images, ec);
  if (ec)
    throw Error("--out-dir " + o.out_dir + ": cannot create " + stage_images.string() + ": " + ec.message());

  struct Written {
    std::int64_t stamp;
    std::string name;
  };
  std::vector<Written> written;
  std::size_t read_count = 0;
  {
    BagReadOptions ro;
    ro.topics = {image_topic.name};
    ro.start = w_start;
    ro.end = w_end;
    bag->read(ro, [&](const BagMessage &m) {
      const std::size_t k = read_count++;
      if (o.progress)
        o.progress(read_count, std::size_t(image_topic.messages));
      if (k % std::size_t(o.every) != 0)
        return true;
      DecodedImage d = compressed ? decodeCompressed(m) : decodeRaw(m);
      if (d.width != int(info->width) || d.height != int(info->height))
        throw Error(image_topic.name + ": the image at t = " + bag_detail::secondsText(d.stamp) + " s is " + std::to_string(d.width) +
                    " x " + std::to_string(d.height) + " pixels, " + info_topic.name + " says " +
                    std::to_string(info->width) + " x " + std::to_string(info->height));
      if (o.camera_frame.empty() && d.frame_id != image_frame)
        throw Error(image_topic.name + ": the image at t = " + bag_detail::secondsText(d.stamp) + " s is in frame " + d.frame_id +
                    ", the first one in " + image_frame + ": give --camera-frame");
      if (d.stamp <= 0)
        throw Error(image_topic.name + ": the image logged at t = " + bag_detail::secondsText(m.log_time) + " s has no stamp");
      const std::string name = std::to_string(d.stamp) + d.ext;
      const fs::path file = stage_images / name;
      if (fs::exists(file))
        throw Error(image_topic.name + ": two images with the stamp " + bag_detail::secondsText(d.stamp) + " s");
      if (compressed) {
        writeFileAtomically(file.string(), std::string(d.bytes.begin(), d.bytes.end()));
      } else {
        std::vector<unsigned char> png;
        if (!cv::imencode(".png", d.mat, png))
          throw Error(file.string() + ": cannot encode the image");
        writeFileAtomically(file.string(), std::string(png.begin(), png.end()));
      }
      written.push_back({d.stamp, name});
      return true;
    });
  }
  counts[image_topic.name] = read_count;
  r.images_read = read_count;
  r.images_kept = written.size();
  std::sort(written.begin(), written.end(), [](const Written &a, const Written &b) { return a.stamp < b.stamp; });

  // The poses at the images' times.
  MotionLog log;
  log.timestamped = true;
  log.yaw_column = false;
  for (std::size_t i = 0; i < motion.size(); ++i) {
    log.samples.push_back(MotionSample::fromPose(long(i), motion[i].M, 0.0));
    log.times.push_back(toSec(motion[i].t));
  }
  ImageList images;
  const fs::path final_images = fs::path(o.out_dir) / "images";
  for (const Written &w : written) {
    images.paths.push_back((final_images / w.name).string());
    images.times.push_back(toSec(w.stamp));
  }
  TimeAlignmentOptions ta;
  ta.time_offset = o.time_offset;
  ta.max_pose_gap = o.max_pose_gap;
  TimeAlignment a = alignMotionToImages(log, images, ta, path + ": " + motion_name, path + ": " + image_topic.name);
  r.skipped_before = a.before;
  r.skipped_after = a.after;
  r.skipped_gap = a.in_gap;
  MotionLog out = std::move(a.log);
#ifdef YAWDEPTH_BAG_TF2
  if (moving_mount) { // each image's camera pose: wMb bMc(t), the mount looked up at the image's time
    MotionLog kept;
    for (std::size_t i = 0; i < out.samples.size(); ++i) {
      ros::Time t;
      t.fromNSec(std::uint64_t(std::max<std::int64_t>(std::llround(out.times[i] * 1e9), 0)));
      vpHomogeneousMatrix bMc_t;
      try {
        bMc_t = fromRos(moving->lookupTransform(body_frame, camera_frame, t), path + ": /tf");
      } catch (const tf2::TransformException &) {
        ++r.skipped_gap; // outside the moving links' readings: no mount there
        continue;
      }
      kept.samples.push_back(MotionSample::fromPose(long(kept.samples.size()), wMv(out.samples[i]) * bMc_t, 0.0));
      kept.images.push_back(out.images[i]);
      kept.times.push_back(out.times[i]);
    }
    if (kept.samples.empty())
      throw Error(path + ": /tf: no image has the mount " + body_frame + " -> " + camera_frame + " at its time");
    kept.yaw_column = false;
    out = std::move(kept);
  }
#endif
  if (use_joint) {
    MotionLog kept;
    kept.yaw_column = true;
    for (std::size_t i = 0; i < out.samples.size(); ++i) {
      double yaw = 0;
      const int s = interpolate(joint, out.times[i], o.max_pose_gap, yaw);
      if (s == -1)
        ++r.skipped_before;
      else if (s == 1)
        ++r.skipped_after;
      else if (s == 2)
        ++r.skipped_gap;
      if (s != 0)
        continue;
      MotionSample x = out.samples[i];
      x.frame = long(kept.samples.size());
      x.yaw = yaw;
      kept.samples.push_back(x);
      kept.images.push_back(out.images[i]);
      kept.times.push_back(out.times[i]);
    }
    if (kept.samples.empty())
      throw Error(path + ": " + joint_topic->name + ": no image has a reading of " + o.joint +
                  " around it (joint readings over [" + sec(joint.front().first) + ", " + sec(joint.back().first) +
                  "] s)");
    out = std::move(kept);
  } else {
    out.yaw_column = false;
  }
  r.images_matched = out.samples.size();
  r.poses = motion.size();
  r.joint_readings = joint.size();
  r.image_first = images.times.front();
  r.image_last = images.times.back();
  r.motion_first = toSec(motion.front().t);
  r.motion_last = toSec(motion.back().t);

  // The images without a pose are not kept.
  {
    std::set<std::string> keep;
    for (const std::string &p : out.images)
      keep.insert(fs::path(p).filename().string());
    for (const Written &w : written)
      if (!keep.count(w.name))
        fs::remove(stage_images / w.name, ec);
  }

  // The text files, in the staging folder (motion.csv's image paths relative to out_dir).
  MotionLog staged = out;
  for (std::string &p : staged.images)
    p = (stage_images / fs::path(p).filename()).string();
  writeMotionCsv((stage.path / "motion.csv").string(), staged);
  saveRosCameraInfoYaml((stage.path / "camera.yaml").string(), camera, fs::path(info_topic.name).parent_path().filename().string());
  RigFile rig;
  rig.camera_pose = vpPoseVector(bMc);
  rig.camera_offset = Eigen::Vector3d(bMc[0][3], bMc[1][3], bMc[2][3]);
  writeRigFile((stage.path / "rig.yaml").string(), rig);

  // Commit: images/ (an older one moved aside, then removed), then the files, each by a rename.
  const fs::path old_images = stage.path / "images.old";
  const bool had_images = fs::exists(final_images, ec);
  if (had_images) {
    if (!fs::is_directory(final_images, ec))
      throw Error("--out-dir " + o.out_dir + ": " + final_images.string() + " exists and is not a folder");
    fs::rename(final_images, old_images, ec);
    if (ec)
      throw Error("--out-dir " + o.out_dir + ": cannot move the earlier images/ aside: " + ec.message());
  }
  fs::rename(stage_images, final_images, ec);
  if (ec) {
    std::error_code e2;
    if (had_images)
      fs::rename(old_images, final_images, e2);
    throw Error("--out-dir " + o.out_dir + ": cannot rename the images into place: " + ec.message());
  }
  r.images_dir = final_images.string();
  r.motion_path = (fs::path(o.out_dir) / "motion.csv").string();
  r.camera_path = (fs::path(o.out_dir) / "camera.yaml").string();
  r.rig_path = (fs::path(o.out_dir) / "rig.yaml").string();
  for (const auto &[from, to] : {std::pair<const char *, std::string>{"motion.csv", r.motion_path},
                                 {"camera.yaml", r.camera_path},
                                 {"rig.yaml", r.rig_path}}) {
    fs::rename(stage.path / from, to, ec);
    if (ec)
      throw Error(to + ": cannot rename into place: " + ec.message());
  }
  out_guard.done = true;

  for (const BagTopic &t : bag->topics())
    if (counts.count(t.name))
      r.topics_used.push_back(t.name + " (" + t.type + "): " + std::to_string(counts[t.name]) + " messages");
  return r;
}

} // namespace yawdepth
