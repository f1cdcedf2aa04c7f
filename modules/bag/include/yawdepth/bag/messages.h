#pragma once
/*!
  \file messages.h
  \brief The message types `import-bag` reads, decoded from either serialization (ROS 1 through
  the message headers of Debian's ROS packages, ROS 2's CDR from its specification), as plain
  structs that need no ROS headers. Field names and units are the ROS messages' own.

  Every decoder throws yawdepth::Error ("<topic>: message at t = <log time> s: <reason>") for a
  message shorter than its fields say, a length field beyond the message, or a wrong type; it never
  reads past BagMessage::size.
*/
#include <array>
#include <cstdint>
#include <string>
#include <vector>
#include <yawdepth/bag/bag.h>

namespace yawdepth {

/*! \brief std_msgs/Header (ROS 1's `seq` dropped). */
struct RosHeader {
  std::int64_t stamp = 0; //!< ns
  std::string frame_id;
};

/*! \brief sensor_msgs/Image. */
struct ImageMessage {
  RosHeader header;
  std::uint32_t height = 0, width = 0;
  std::string encoding; //!< "mono8", "rgb8", "bgr8", "mono16", ... (as written)
  bool is_bigendian = false;
  std::uint32_t step = 0; //!< bytes per row
  std::vector<std::uint8_t> data;
};

/*! \brief sensor_msgs/CompressedImage. */
struct CompressedImageMessage {
  RosHeader header;
  std::string format; //!< "jpeg", "png", or image_transport's "rgb8; jpeg compressed bgr8"
  std::vector<std::uint8_t> data;
};

/*! \brief sensor_msgs/CameraInfo (ROS 1 field names; ROS 2's lower-case d, k, r, p are the same fields). */
struct CameraInfoMessage {
  RosHeader header;
  std::uint32_t height = 0, width = 0;
  std::string distortion_model; //!< "plumb_bob", "rational_polynomial", "equidistant", ...
  std::vector<double> D;
  std::array<double, 9> K{};
  std::array<double, 9> R{};
  std::array<double, 12> P{};
  std::uint32_t binning_x = 0, binning_y = 0;
  std::uint32_t roi_x_offset = 0, roi_y_offset = 0, roi_height = 0, roi_width = 0;
  bool roi_do_rectify = false;
};

/*! \brief geometry_msgs/Pose: a position (m) and a Hamilton quaternion (x, y, z, w). */
struct RosPose {
  std::array<double, 3> position{};
  std::array<double, 4> orientation{0, 0, 0, 1}; //!< x, y, z, w
};

/*! \brief geometry_msgs/PoseStamped or PoseWithCovarianceStamped (the covariance kept, row-major 6x6, or all zero). */
struct PoseMessage {
  RosHeader header;
  RosPose pose;
  std::array<double, 36> covariance{};
};

/*! \brief nav_msgs/Odometry: the pose of child_frame_id in header.frame_id (twist dropped). */
struct OdometryMessage {
  RosHeader header;
  std::string child_frame_id;
  RosPose pose;
  std::array<double, 36> covariance{};
};

/*! \brief geometry_msgs/TransformStamped: the pose of child_frame_id in header.frame_id. */
struct TransformMessage {
  RosHeader header;
  std::string child_frame_id;
  std::array<double, 3> translation{};
  std::array<double, 4> rotation{0, 0, 0, 1}; //!< x, y, z, w
};

/*! \brief tf2_msgs/TFMessage (`/tf`, `/tf_static`). */
struct TfMessage {
  std::vector<TransformMessage> transforms;
};

/*! \brief sensor_msgs/JointState (rad or m; velocity and effort may be empty). */
struct JointStateMessage {
  RosHeader header;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;
};

/*! @name Decoders: each checks the topic's type and dispatches on its encoding. */
///@{
ImageMessage decodeImage(const BagMessage &m);
CompressedImageMessage decodeCompressedImage(const BagMessage &m);
CameraInfoMessage decodeCameraInfo(const BagMessage &m);
/*! \brief geometry_msgs/PoseStamped or PoseWithCovarianceStamped, by the topic's type. */
PoseMessage decodePose(const BagMessage &m);
OdometryMessage decodeOdometry(const BagMessage &m);
TfMessage decodeTf(const BagMessage &m);
JointStateMessage decodeJointState(const BagMessage &m);
///@}

} // namespace yawdepth
