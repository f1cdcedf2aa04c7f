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
#include <yawdepth/camera/camera_model.h>

namespace yawdepth {

/*! \brief std_msgs/Header (ROS 1's `seq` dropped). */
struct RosHeader {
  std::int64_t stamp = 0; //!< the stamp (ns since 1970, the sender's clock)
  std::string frame_id;   //!< the frame the data are in
};

/*! \brief sensor_msgs/Image. */
struct ImageMessage {
  RosHeader header;               //!< stamp and optical frame
  std::uint32_t height = 0;       //!< rows (px)
  std::uint32_t width = 0;        //!< columns (px)
  std::string encoding;           //!< "mono8", "rgb8", "bgr8", "mono16", ... (as written)
  bool is_bigendian = false;      //!< byte order of multi-byte pixels
  std::uint32_t step = 0;         //!< bytes per row
  std::vector<std::uint8_t> data; //!< step x height bytes
};

/*! \brief sensor_msgs/CompressedImage. */
struct CompressedImageMessage {
  RosHeader header;               //!< stamp and optical frame
  std::string format;             //!< "jpeg", "png", or image_transport's "rgb8; jpeg compressed bgr8"
  std::vector<std::uint8_t> data; //!< the JPEG or PNG file's bytes
};

/*! \brief sensor_msgs/CameraInfo (ROS 1 field names; ROS 2's lower-case d, k, r, p are the same fields). */
struct CameraInfoMessage {
  RosHeader header;             //!< stamp and optical frame
  std::uint32_t height = 0;     //!< image rows (px)
  std::uint32_t width = 0;      //!< image columns (px)
  std::string distortion_model; //!< "plumb_bob", "rational_polynomial", "equidistant", ...
  std::vector<double> D;        //!< distortion coefficients
  std::array<double, 9> K{};    //!< intrinsic matrix, row-major
  std::array<double, 9> R{};    //!< rectification rotation, row-major
  std::array<double, 12> P{};   //!< projection matrix, row-major 3x4
  std::uint32_t binning_x = 0;  //!< horizontal binning (0 or 1: none)
  std::uint32_t binning_y = 0;  //!< vertical binning (0 or 1: none)
  std::uint32_t roi_x_offset = 0; //!< region of interest: left column
  std::uint32_t roi_y_offset = 0; //!< region of interest: top row
  std::uint32_t roi_height = 0;   //!< region of interest: rows (0: the whole image)
  std::uint32_t roi_width = 0;    //!< region of interest: columns (0: the whole image)
  bool roi_do_rectify = false;    //!< whether the region is to be rectified
};

/*! \brief geometry_msgs/Pose: a position (m) and a Hamilton quaternion (x, y, z, w). */
struct RosPose {
  std::array<double, 3> position{};              //!< x, y, z (m)
  std::array<double, 4> orientation{0, 0, 0, 1}; //!< x, y, z, w
};

/*! \brief geometry_msgs/PoseStamped or PoseWithCovarianceStamped. */
struct PoseMessage {
  RosHeader header;                   //!< stamp and the frame the pose is in
  RosPose pose;                       //!< the pose
  std::array<double, 36> covariance{}; //!< row-major 6x6 (PoseWithCovarianceStamped), or all zero
};

/*! \brief nav_msgs/Odometry: the pose of child_frame_id in header.frame_id (twist dropped). */
struct OdometryMessage {
  RosHeader header;                    //!< stamp and the world frame
  std::string child_frame_id;          //!< the body frame
  RosPose pose;                        //!< the body's pose in the world
  std::array<double, 36> covariance{}; //!< the pose's covariance, row-major 6x6
};

/*! \brief geometry_msgs/TransformStamped: the pose of child_frame_id in header.frame_id. */
struct TransformMessage {
  RosHeader header;                           //!< stamp and the parent frame
  std::string child_frame_id;                 //!< the child frame
  std::array<double, 3> translation{};        //!< the child's origin in the parent (m)
  std::array<double, 4> rotation{0, 0, 0, 1}; //!< x, y, z, w
};

/*! \brief tf2_msgs/TFMessage (`/tf`, `/tf_static`). */
struct TfMessage {
  std::vector<TransformMessage> transforms; //!< the transforms, as sent
};

/*! \brief sensor_msgs/JointState (rad or m; velocity and effort may be empty). */
struct JointStateMessage {
  RosHeader header;              //!< stamp
  std::vector<std::string> name; //!< the joints
  std::vector<double> position;  //!< one per joint, or empty
  std::vector<double> velocity;  //!< one per joint, or empty
  std::vector<double> effort;    //!< one per joint, or empty
};

/*! @name Decoders: each checks the topic's type and dispatches on its encoding. */
///@{
/*! \brief sensor_msgs/Image. */
ImageMessage decodeImage(const BagMessage &m);
/*! \brief sensor_msgs/CompressedImage. */
CompressedImageMessage decodeCompressedImage(const BagMessage &m);
/*! \brief sensor_msgs/CameraInfo. */
CameraInfoMessage decodeCameraInfo(const BagMessage &m);
/*! \brief geometry_msgs/PoseStamped or PoseWithCovarianceStamped, by the topic's type. */
PoseMessage decodePose(const BagMessage &m);
/*! \brief nav_msgs/Odometry. */
OdometryMessage decodeOdometry(const BagMessage &m);
/*! \brief tf2_msgs/TFMessage. */
TfMessage decodeTf(const BagMessage &m);
/*! \brief sensor_msgs/JointState. */
JointStateMessage decodeJointState(const BagMessage &m);
///@}

/*!
  \brief The camera of a camera_info (import-bag's and the ROS node's): K's focal lengths and
  principal point; `plumb_bob` (trailing zero coefficients dropped) and `rational_polynomial` (its
  thin-prism terms must be zero) as Brown, `equidistant` as Kannala-Brandt, with the image size;
  then checkCameraPlausible(). Throws yawdepth::Error "<topic>: camera_info ..." for an all-zero or
  non-finite K, another distortion model, or an implausible camera.
*/
CameraModel cameraFromCameraInfo(const CameraInfoMessage &info, const std::string &topic);
/*! \brief Whether two camera_info give the same calibration (size, distortion model, D and K). */
bool sameCalibration(const CameraInfoMessage &a, const CameraInfoMessage &b);

} // namespace yawdepth
