// The decoders of messages.h: check the topic's type, dispatch on its serialization.
#include "readers.h"

#include <cstdio>
#include <yawdepth/error.h>

namespace yawdepth {
namespace bag_detail {

std::string secondsText(std::int64_t ns)
{
  char t[64];
  std::snprintf(t, sizeof t, "%.9f", double(ns) * 1e-9);
  return t;
}

std::string messageWhere(const BagMessage &m)
{
  return (m.topic ? m.topic->name : std::string("?")) + ": message at t = " + secondsText(m.log_time) + " s: ";
}

void requireType(const BagMessage &m, std::initializer_list<const char *> types)
{
  if (!m.topic)
    throw Error("bag message without a topic");
  std::string names;
  for (const char *t : types) {
    if (m.topic->type == t)
      return;
    names += (names.empty() ? "" : " or ") + std::string(t);
  }
  throw Error(m.topic->name + ": is " + m.topic->type + ", not " + names);
}

} // namespace bag_detail

using namespace bag_detail;

namespace {

#ifdef YAWDEPTH_BAG_ROS1
#define YAWDEPTH_DISPATCH(fn, m) ((m).topic->encoding == BagEncoding::Ros1 ? ros1::fn(m) : cdr::fn(m))
#else
template <typename F> auto cdrOnly(const BagMessage &m, F f)
{
  if (m.topic->encoding == BagEncoding::Ros1)
    throw Error(messageWhere(m) + "ROS 1 serialization, and this build was made without the ROS 1 message headers");
  return f(m);
}
#define YAWDEPTH_DISPATCH(fn, m) cdrOnly(m, [](const BagMessage &x) { return cdr::fn(x); })
#endif

} // namespace

ImageMessage decodeImage(const BagMessage &m)
{
  requireType(m, {"sensor_msgs/Image"});
  return YAWDEPTH_DISPATCH(decodeImage, m);
}
CompressedImageMessage decodeCompressedImage(const BagMessage &m)
{
  requireType(m, {"sensor_msgs/CompressedImage"});
  return YAWDEPTH_DISPATCH(decodeCompressedImage, m);
}
CameraInfoMessage decodeCameraInfo(const BagMessage &m)
{
  requireType(m, {"sensor_msgs/CameraInfo"});
  return YAWDEPTH_DISPATCH(decodeCameraInfo, m);
}
PoseMessage decodePose(const BagMessage &m)
{
  requireType(m, {"geometry_msgs/PoseStamped", "geometry_msgs/PoseWithCovarianceStamped"});
  return YAWDEPTH_DISPATCH(decodePose, m);
}
OdometryMessage decodeOdometry(const BagMessage &m)
{
  requireType(m, {"nav_msgs/Odometry"});
  return YAWDEPTH_DISPATCH(decodeOdometry, m);
}
TfMessage decodeTf(const BagMessage &m)
{
  requireType(m, {"tf2_msgs/TFMessage"});
  return YAWDEPTH_DISPATCH(decodeTf, m);
}
JointStateMessage decodeJointState(const BagMessage &m)
{
  requireType(m, {"sensor_msgs/JointState"});
  return YAWDEPTH_DISPATCH(decodeJointState, m);
}

} // namespace yawdepth
