#pragma once
// Shared by the bag fuzz targets: every message of a bag decoded by its type's decoder, each
// decoder's own yawdepth::Error caught (the next message is still read), results checked.
#include <cstdint>
#include <memory>
#include <yawdepth/bag/bag.h>
#include <yawdepth/bag/messages.h>
#include <yawdepth/error.h>

namespace yawdepth_fuzz {

/* Decodes `m` by its topic's type; traps when a result is larger than the message could hold. */
inline void decodeAny(const yawdepth::BagMessage &m)
{
  using namespace yawdepth;
  const std::string &t = m.topic->type;
  try {
    if (t == "sensor_msgs/Image") {
      if (decodeImage(m).data.size() > m.size)
        __builtin_trap();
    } else if (t == "sensor_msgs/CompressedImage") {
      if (decodeCompressedImage(m).data.size() > m.size)
        __builtin_trap();
    } else if (t == "sensor_msgs/CameraInfo") {
      if (decodeCameraInfo(m).D.size() * 8 > m.size)
        __builtin_trap();
    } else if (t == "geometry_msgs/PoseStamped" || t == "geometry_msgs/PoseWithCovarianceStamped") {
      decodePose(m);
    } else if (t == "nav_msgs/Odometry") {
      decodeOdometry(m);
    } else if (t == "tf2_msgs/TFMessage") {
      if (decodeTf(m).transforms.size() * 72 > m.size)
        __builtin_trap();
    } else if (t == "sensor_msgs/JointState") {
      const JointStateMessage j = decodeJointState(m);
      if ((j.position.size() + j.velocity.size() + j.effort.size()) * 8 > m.size)
        __builtin_trap();
    }
  } catch (const Error &) {
  }
}

/* Opens the bag at `path` and reads it whole: the topics, a selective read, every message decoded. */
inline void readBag(const std::string &path)
{
  using namespace yawdepth;
  const std::unique_ptr<BagReader> r = openBag(path);
  const std::vector<BagTopic> &topics = r->topics();
  r->topicList();
  r->read({}, [&](const BagMessage &m) {
    if (!m.topic || m.topic < topics.data() || m.topic >= topics.data() + topics.size())
      __builtin_trap();
    decodeAny(m);
    return true;
  });
  if (!topics.empty()) {
    BagReadOptions o;
    o.topics = {topics.front().name};
    o.start = 0;
    std::size_t n = 0;
    r->read(o, [&](const BagMessage &m) {
      if (m.topic->name != topics.front().name || m.log_time < 0)
        __builtin_trap();
      return ++n < 5;
    });
  }
}

} // namespace yawdepth_fuzz
