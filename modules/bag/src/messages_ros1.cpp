// ROS 1 serialization, decoded by the message headers of Debian's ROS packages.
#include "readers.h"

#include <algorithm>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/serialization.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <tf2_msgs/TFMessage.h>
#include <yawdepth/error.h>

namespace yawdepth {
namespace bag_detail {
namespace ros1 {

namespace {

/* The layout of each message, checked before ROS deserializes it (ros::serialization resizes a
   vector by its length field before it checks the bytes are there: a corrupt length would
   allocate gigabytes). Tokens: H header (seq, stamp, frame_id), s string, S string[], c uint8,
   u uint32, fN N float64, B uint8[], D float64[], V( ... ) an array of the bracketed layout. */
const char *layoutOf(const std::string &type)
{
  if (type == "sensor_msgs/Image")
    return "H u u s c u B";
  if (type == "sensor_msgs/CompressedImage")
    return "H s B";
  if (type == "sensor_msgs/CameraInfo")
    return "H u u s D f9 f9 f12 u u u u u u c";
  if (type == "geometry_msgs/PoseStamped")
    return "H f7";
  if (type == "geometry_msgs/PoseWithCovarianceStamped")
    return "H f43";
  if (type == "nav_msgs/Odometry")
    return "H s f43 f42";
  if (type == "tf2_msgs/TFMessage")
    return "V( H s f7 )";
  if (type == "sensor_msgs/JointState")
    return "H S D D D";
  return nullptr;
}

/* Walks `layout` from token `k` over data[pos, size); false when a length runs past the end. */
bool walk(const std::vector<std::string> &tok, std::size_t &k, std::size_t end_tok, const std::uint8_t *data,
          std::size_t size, std::size_t &pos)
{
  auto take = [&](std::size_t n) {
    if (n > size - pos)
      return false;
    pos += n;
    return true;
  };
  auto u32 = [&](std::uint32_t &v) {
    if (size - pos < 4)
      return false;
    v = std::uint32_t(data[pos]) | std::uint32_t(data[pos + 1]) << 8 | std::uint32_t(data[pos + 2]) << 16 |
        std::uint32_t(data[pos + 3]) << 24;
    pos += 4;
    return true;
  };
  std::uint32_t n = 0;
  while (k < end_tok) {
    const std::string &t = tok[k++];
    if (t == "H") {
      if (!take(12) || !u32(n) || !take(n))
        return false;
    } else if (t == "s" || t == "B") {
      if (!u32(n) || !take(n))
        return false;
    } else if (t == "c") {
      if (!take(1))
        return false;
    } else if (t == "u") {
      if (!take(4))
        return false;
    } else if (t[0] == 'f') {
      if (!take(8 * std::size_t(std::stoul(t.substr(1)))))
        return false;
    } else if (t == "D") {
      if (!u32(n) || !take(8 * std::size_t(n)))
        return false;
    } else if (t == "S") {
      if (!u32(n) || n > (size - pos) / 4)
        return false;
      for (std::uint32_t i = 0; i < n; ++i) {
        std::uint32_t len = 0;
        if (!u32(len) || !take(len))
          return false;
      }
    } else if (t == "V(") {
      std::size_t close = k;
      while (tok[close] != ")")
        ++close;
      if (!u32(n) || n > (size - pos) / 4)
        return false;
      for (std::uint32_t i = 0; i < n; ++i) {
        std::size_t kk = k;
        if (!walk(tok, kk, close, data, size, pos))
          return false;
      }
      k = close + 1;
    }
  }
  return true;
}

void checkLayout(const BagMessage &m)
{
  const char *layout = layoutOf(m.topic->type);
  if (!layout)
    return;
  std::vector<std::string> tok;
  for (const char *p = layout; *p;) {
    while (*p == ' ')
      ++p;
    const char *q = p;
    while (*q && *q != ' ')
      ++q;
    if (q > p)
      tok.emplace_back(p, q);
    p = q;
  }
  std::size_t k = 0, pos = 0;
  if (!walk(tok, k, tok.size(), m.data, m.size, pos))
    throw Error(messageWhere(m) + "shorter than its fields say, or a length field beyond the message (" +
                std::to_string(m.size) + " bytes)");
}

/* The ROS message of `m`, deserialized; a short or inconsistent message is an Error. */
template <typename T> T deserialize(const BagMessage &m)
{
  T msg;
  checkLayout(m);
  try {
    ros::serialization::IStream in(const_cast<std::uint8_t *>(m.data), std::uint32_t(m.size));
    ros::serialization::deserialize(in, msg);
    if (in.getLength() != 0)
      throw Error(messageWhere(m) + std::to_string(in.getLength()) + " bytes left after the message (a wrong type?)");
  } catch (const ros::serialization::StreamOverrunException &) {
    throw Error(messageWhere(m) + "shorter than its fields say (" + std::to_string(m.size) + " bytes)");
  } catch (const std::bad_alloc &) {
    throw Error(messageWhere(m) + "a length field beyond the message");
  } catch (const std::length_error &) {
    throw Error(messageWhere(m) + "a length field beyond the message");
  }
  return msg;
}

RosHeader header(const std_msgs::Header &h)
{
  RosHeader r;
  r.stamp = std::int64_t(h.stamp.toNSec());
  r.frame_id = h.frame_id;
  return r;
}

RosPose pose(const geometry_msgs::Pose &p)
{
  RosPose r;
  r.position = {p.position.x, p.position.y, p.position.z};
  r.orientation = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
  return r;
}

} // namespace

ImageMessage decodeImage(const BagMessage &m)
{
  auto s = deserialize<sensor_msgs::Image>(m);
  ImageMessage r;
  r.header = header(s.header);
  r.height = s.height;
  r.width = s.width;
  r.encoding = s.encoding;
  r.is_bigendian = s.is_bigendian != 0;
  r.step = s.step;
  r.data = std::move(s.data);
  return r;
}

CompressedImageMessage decodeCompressedImage(const BagMessage &m)
{
  auto s = deserialize<sensor_msgs::CompressedImage>(m);
  CompressedImageMessage r;
  r.header = header(s.header);
  r.format = s.format;
  r.data = std::move(s.data);
  return r;
}

CameraInfoMessage decodeCameraInfo(const BagMessage &m)
{
  const auto s = deserialize<sensor_msgs::CameraInfo>(m);
  CameraInfoMessage r;
  r.header = header(s.header);
  r.height = s.height;
  r.width = s.width;
  r.distortion_model = s.distortion_model;
  r.D = s.D;
  std::copy(s.K.begin(), s.K.end(), r.K.begin());
  std::copy(s.R.begin(), s.R.end(), r.R.begin());
  std::copy(s.P.begin(), s.P.end(), r.P.begin());
  r.binning_x = s.binning_x;
  r.binning_y = s.binning_y;
  r.roi_x_offset = s.roi.x_offset;
  r.roi_y_offset = s.roi.y_offset;
  r.roi_height = s.roi.height;
  r.roi_width = s.roi.width;
  r.roi_do_rectify = s.roi.do_rectify != 0;
  return r;
}

PoseMessage decodePose(const BagMessage &m)
{
  PoseMessage r;
  if (m.topic->type == "geometry_msgs/PoseStamped") {
    const auto s = deserialize<geometry_msgs::PoseStamped>(m);
    r.header = header(s.header);
    r.pose = pose(s.pose);
  } else {
    const auto s = deserialize<geometry_msgs::PoseWithCovarianceStamped>(m);
    r.header = header(s.header);
    r.pose = pose(s.pose.pose);
    std::copy(s.pose.covariance.begin(), s.pose.covariance.end(), r.covariance.begin());
  }
  return r;
}

OdometryMessage decodeOdometry(const BagMessage &m)
{
  const auto s = deserialize<nav_msgs::Odometry>(m);
  OdometryMessage r;
  r.header = header(s.header);
  r.child_frame_id = s.child_frame_id;
  r.pose = pose(s.pose.pose);
  std::copy(s.pose.covariance.begin(), s.pose.covariance.end(), r.covariance.begin());
  return r;
}

TfMessage decodeTf(const BagMessage &m)
{
  const auto s = deserialize<tf2_msgs::TFMessage>(m);
  TfMessage r;
  r.transforms.reserve(s.transforms.size());
  for (const auto &t : s.transforms) {
    TransformMessage x;
    x.header = header(t.header);
    x.child_frame_id = t.child_frame_id;
    x.translation = {t.transform.translation.x, t.transform.translation.y, t.transform.translation.z};
    x.rotation = {t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w};
    r.transforms.push_back(std::move(x));
  }
  return r;
}

JointStateMessage decodeJointState(const BagMessage &m)
{
  auto s = deserialize<sensor_msgs::JointState>(m);
  JointStateMessage r;
  r.header = header(s.header);
  r.name = std::move(s.name);
  r.position = std::move(s.position);
  r.velocity = std::move(s.velocity);
  r.effort = std::move(s.effort);
  return r;
}

} // namespace ros1
} // namespace bag_detail
} // namespace yawdepth
