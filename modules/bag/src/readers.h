#pragma once
// Private to the bag module: the readers openBag() dispatches to, each in its own file and built
// only when its library was found (YAWDEPTH_BAG_ROS1, _MCAP, _DB3 from CMake), and the decoders of
// each serialization that messages.cpp dispatches to.
#include <functional>
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

/*! openFile() of bag.cpp: the container of `files` (told by the first one's bytes), named `name`. */
using OpenContainer = std::function<std::unique_ptr<BagReader>(const std::string &first, const std::string &name,
                                                               const std::vector<std::string> &files)>;
/*! Whether `path` starts with a zstd frame (rosbag2's FILE compression). rosbag2_compression.cpp, with
    YAWDEPTH_BAG_ZSTD. */
bool zstdFile(const std::string &path);
/*! rosbag2's compression undone (rosbag2_compression.cpp): the zstd storage files decompressed into
    scratch files, the container opened by `open`, zstd-compressed messages of a ROS 2 container
    decompressed as they are read; every message names the files given. */
std::unique_ptr<BagReader> openRosbag2(const std::string &name, const std::vector<std::string> &files,
                                       const OpenContainer &open);

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
