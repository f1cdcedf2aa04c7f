#pragma once
// Private to the bag module: the readers openBag() dispatches to, each in its own file and built
// only when its library was found (YAWDEPTH_BAG_ROS1, _MCAP, _DB3 from CMake), and the decoders of
// each serialization that messages.cpp dispatches to.
#include <memory>
#include <string>
#include <vector>
#include <yawdepth/bag/bag.h>
#include <yawdepth/bag/messages.h>

namespace yawdepth {
namespace bag_detail {

/*! `path` for the messages; `files` the storage files in order (one for a plain file). */
std::unique_ptr<BagReader> openRos1(const std::string &path);
std::unique_ptr<BagReader> openMcap(const std::string &path, const std::vector<std::string> &files);
std::unique_ptr<BagReader> openDb3(const std::string &path, const std::vector<std::string> &files);

/*! A ROS time (ns) as seconds with nine decimals, for the messages. */
std::string secondsText(std::int64_t ns);
/*! "<topic>: message at t = <log time> s: " for the decoders' messages. */
std::string messageWhere(const BagMessage &m);
/*! Throws unless the message's topic has one of `types` (ROS 1 spelling). */
void requireType(const BagMessage &m, std::initializer_list<const char *> types);

namespace ros1 { // messages_ros1.cpp, with YAWDEPTH_BAG_ROS1
ImageMessage decodeImage(const BagMessage &m);
CompressedImageMessage decodeCompressedImage(const BagMessage &m);
CameraInfoMessage decodeCameraInfo(const BagMessage &m);
PoseMessage decodePose(const BagMessage &m);
OdometryMessage decodeOdometry(const BagMessage &m);
TfMessage decodeTf(const BagMessage &m);
JointStateMessage decodeJointState(const BagMessage &m);
} // namespace ros1

namespace cdr { // messages_cdr.cpp, always built
ImageMessage decodeImage(const BagMessage &m);
CompressedImageMessage decodeCompressedImage(const BagMessage &m);
CameraInfoMessage decodeCameraInfo(const BagMessage &m);
PoseMessage decodePose(const BagMessage &m);
OdometryMessage decodeOdometry(const BagMessage &m);
TfMessage decodeTf(const BagMessage &m);
JointStateMessage decodeJointState(const BagMessage &m);
} // namespace cdr

} // namespace bag_detail
} // namespace yawdepth
