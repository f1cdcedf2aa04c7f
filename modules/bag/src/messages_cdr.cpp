// The decoders of messages.h for ROS 2's CDR, with the ROS 2 field layouts (std_msgs/Header is
// stamp and frame_id; builtin_interfaces/Time is int32 sec, uint32 nanosec). Every field of a
// message is read, the dropped ones too (Odometry's twist), so that a message shorter than its type
// is refused whatever is kept; bytes after the last field (padding) are allowed.
#include "cdr.h"
#include "readers.h"

namespace yawdepth {
namespace bag_detail {
namespace cdr {

namespace {

Reader open(const BagMessage &m)
{
  return Reader(m.data, m.size, messageWhere(m));
}

RosHeader header(Reader &r)
{
  RosHeader h;
  h.stamp = r.time();
  h.frame_id = r.string();
  return h;
}

RosPose pose(Reader &r)
{
  RosPose p;
  r.doubles(p.position);
  r.doubles(p.orientation);
  return p;
}

} // namespace

ImageMessage decodeImage(const BagMessage &m)
{
  Reader r = open(m);
  ImageMessage i;
  i.header = header(r);
  i.height = r.u32();
  i.width = r.u32();
  i.encoding = r.string();
  i.is_bigendian = r.u8() != 0;
  i.step = r.u32();
  i.data = r.bytes("data");
  return i;
}

CompressedImageMessage decodeCompressedImage(const BagMessage &m)
{
  Reader r = open(m);
  CompressedImageMessage c;
  c.header = header(r);
  c.format = r.string();
  c.data = r.bytes("data");
  return c;
}

CameraInfoMessage decodeCameraInfo(const BagMessage &m)
{
  Reader r = open(m);
  CameraInfoMessage c;
  c.header = header(r);
  c.height = r.u32();
  c.width = r.u32();
  c.distortion_model = r.string();
  c.D = r.doubles("d");
  r.doubles(c.K);
  r.doubles(c.R);
  r.doubles(c.P);
  c.binning_x = r.u32();
  c.binning_y = r.u32();
  c.roi_x_offset = r.u32();
  c.roi_y_offset = r.u32();
  c.roi_height = r.u32();
  c.roi_width = r.u32();
  c.roi_do_rectify = r.boolean();
  return c;
}

PoseMessage decodePose(const BagMessage &m)
{
  Reader r = open(m);
  PoseMessage p;
  p.header = header(r);
  p.pose = pose(r);
  if (m.topic->type == "geometry_msgs/PoseWithCovarianceStamped")
    r.doubles(p.covariance);
  return p;
}

OdometryMessage decodeOdometry(const BagMessage &m)
{
  Reader r = open(m);
  OdometryMessage o;
  o.header = header(r);
  o.child_frame_id = r.string();
  o.pose = pose(r);
  r.doubles(o.covariance);
  r.skipDoubles(6 + 36); // twist: linear, angular, covariance
  return o;
}

TfMessage decodeTf(const BagMessage &m)
{
  Reader r = open(m);
  TfMessage tf;
  // A TransformStamped takes at least 8 (stamp) + 4 (frame_id) + 4 (child) + 56 (transform) bytes.
  const std::uint32_t n = r.count(72, "transforms");
  tf.transforms.resize(n);
  for (TransformMessage &t : tf.transforms) {
    t.header = header(r);
    t.child_frame_id = r.string();
    r.doubles(t.translation);
    r.doubles(t.rotation);
  }
  return tf;
}

JointStateMessage decodeJointState(const BagMessage &m)
{
  Reader r = open(m);
  JointStateMessage j;
  j.header = header(r);
  j.name = r.strings("name");
  j.position = r.doubles("position");
  j.velocity = r.doubles("velocity");
  j.effort = r.doubles("effort");
  return j;
}

} // namespace cdr
} // namespace bag_detail
} // namespace yawdepth
