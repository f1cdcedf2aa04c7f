// libFuzzer target: a ROS 1 bag (the structural check, rosbag_storage behind it) opened, every
// message read and decoded by its topic's type. The input is the whole file.
#include "fuzz_common.h"

#include <yawdepth/bag/bag.h>
#include <yawdepth/bag/messages.h>
#include <yawdepth/error.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".bag");
  const std::string &path = file.write(data, size);
  try {
    auto bag = yawdepth::openBag(path);
    bag->read({}, [&](const yawdepth::BagMessage &m) {
      if (!m.topic || (m.size > 0 && !m.data))
        __builtin_trap();
      const std::string &type = m.topic->type;
      try {
        if (type == "sensor_msgs/Image")
          yawdepth::decodeImage(m);
        else if (type == "sensor_msgs/CompressedImage")
          yawdepth::decodeCompressedImage(m);
        else if (type == "sensor_msgs/CameraInfo")
          yawdepth::decodeCameraInfo(m);
        else if (type == "nav_msgs/Odometry")
          yawdepth::decodeOdometry(m);
        else if (type == "tf2_msgs/TFMessage")
          yawdepth::decodeTf(m);
        else if (type == "sensor_msgs/JointState")
          yawdepth::decodeJointState(m);
        else if (type == "geometry_msgs/PoseStamped" || type == "geometry_msgs/PoseWithCovarianceStamped")
          yawdepth::decodePose(m);
      } catch (const yawdepth::Error &) {
      }
      return true;
    });
  } catch (const yawdepth::Error &) {
  }
  return 0;
}
