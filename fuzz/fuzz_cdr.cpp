// libFuzzer target: the CDR decoders of messages.h on any payload. The first byte picks the type;
// the rest is the message (its CDR encapsulation header first).
#include "fuzz_bag_common.h"

#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  if (size < 1)
    return 0;
  static const char *kTypes[] = {"sensor_msgs/Image",       "sensor_msgs/CompressedImage",
                                 "sensor_msgs/CameraInfo",  "geometry_msgs/PoseStamped",
                                 "geometry_msgs/PoseWithCovarianceStamped", "nav_msgs/Odometry",
                                 "tf2_msgs/TFMessage",      "sensor_msgs/JointState"};
  yawdepth::BagTopic topic;
  topic.name = "/fuzz";
  topic.type = kTypes[data[0] % 8];
  topic.encoding = yawdepth::BagEncoding::Cdr;
  // A heap copy of exactly the payload: AddressSanitizer sees any read past it.
  const std::vector<std::uint8_t> payload(data + 1, data + size);
  yawdepth::BagMessage m;
  m.topic = &topic;
  m.log_time = 1;
  m.data = payload.data();
  m.size = payload.size();
  yawdepth_fuzz::decodeAny(m);
  return 0;
}
