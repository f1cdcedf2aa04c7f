// libFuzzer target: a ROS 1 bag (the structural check, rosbag_storage behind it) opened, every
// message read and decoded by its topic's type; a bag with the seeds' /cam/image_raw and /odom is
// also imported (importBag into a temporary folder). The input is the whole file.
#include "fuzz_common.h"

#include <filesystem>
#include <unistd.h>
#include <yawdepth/bag/bag.h>
#include <yawdepth/bag/import.h>
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
    if (bag->topic("/cam/image_raw") && bag->topic("/odom")) {
      static const std::string out = path + ".out";
      yawdepth::BagImportOptions o;
      o.bag = path;
      o.out_dir = out;
      o.image_topic = "/cam/image_raw";
      o.odom_topic = "/odom";
      o.camera_frame = "base_link"; // the seeds have no /tf_static: the camera is the body
      o.max_pose_gap = 1.0;
      std::error_code ec;
      std::filesystem::remove_all(out, ec);
      try {
        yawdepth::importBag(o);
      } catch (const yawdepth::Error &) {
      }
      std::filesystem::remove_all(out, ec);
    }
  } catch (const yawdepth::Error &) {
  }
  return 0;
}
