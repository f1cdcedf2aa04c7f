/*
  make_drive_bag: issue 37's rendered drive (benchmarks/online_drive.h, seed 7) as a ROS 1 bag that
  looks like a real robot's recording, written with rosbag_storage (rosbag::Bag), and its truth as
  JSON. Build tree only (not installed): the ROS node's test bag, and tests/ros/drive_bag_measure.sh
  measures it with `yawdepth measure --bag`.

    make_drive_bag --out drive.bag --truth truth.json [--seconds 6] [--latency 0.030] [--pan-in-tf]
                   [--raw-images]

  Frames (names carry frames: odomMb is base_link's pose in odom, ...):
  - w'  the drive's world (its motion rows): yawdepth's vision frame at t = 0, x right, y DOWN, z forward.
  - v   the drive's vision frame: on the pan axis, heading about its +Y (down), the camera's yaw about
        +Y too (positive turns the optical axis toward +x, i.e. RIGHT); the camera at yaw 0 has v's
        axes, its centre at t0 = (-0.05, 0, 0) in v.
  - odom       REP 105 world, z up; base_link REP 103 body: x forward, y left, z up, on the floor.
  - pan        the pan joint's child: turns about base_link's +z (right-handed: positive = LEFT) by
               q = -yaw, its axis through kJointOrigin in base_link; not in TF (q is on /joint_states).
  - camera_optical  REP 103 optical: z forward, x right, y down (v's axes at q = 0).
  The robot drives forward along base_link's +x = v's +x (the image's right), the camera looks to the
  robot's left (base_link +y = v's +z) at the wall 2 m away. Every ROS pose is computed here from
  explicit rotation matrices and checked, for every image, against yawdepth's wMc(rig, pose) up to one
  constant odomMw' (1e-9); the program exits 1 otherwise.

  Topics (all stamps T0 + motion time, T0 = 1.7e9 s (November 2023, an epoch time as a robot's); each message logged at its stamp plus a transport
  delay, 2 ms, images 5 ms; /tf_static logged at T0; written in log-time order, uncompressed chunks):
    /tf_static                    tf2_msgs/TFMessage base_link -> camera_optical at q = 0, latched, once
    /tf                           tf2_msgs/TFMessage odom -> base_link, 100 Hz
    /odom                         nav_msgs/Odometry odom -> base_link with its twist, 100 Hz
    /joint_states                 sensor_msgs/JointState [left_wheel, pan_joint, right_wheel], 50 Hz
    /camera/image_raw/compressed  sensor_msgs/CompressedImage JPEG (quality 90) mono8, 30 Hz, stamped
                                  at the capture (motion) time + --latency (a driver stamping on arrival)
    /camera/camera_info           sensor_msgs/CameraInfo with each image (plumb_bob, zero distortion)
  --pan-in-tf: the pan as robot_state_publisher gives it: /tf_static holds pan_link -> camera_optical,
  /tf base_link -> pan_link at each joint state (50 Hz, its stamp); /joint_states is still written.
  --raw-images: /camera/image_raw sensor_msgs/Image mono8 instead of the compressed topic.
*/
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include <boost/make_shared.hpp>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <opencv2/imgcodecs.hpp>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <tf2_msgs/TFMessage.h>

#include "online_drive.h"

namespace drive = yawdepth::bench::drive;
using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr unsigned kSeed = 7;                   // held apart from test_online's 37 and bench_online's 11
constexpr double kT0 = 1.7e9; // s: the bag's time of the drive's motion time 0 (an epoch time, as a real recording's)
constexpr double kSmallDelay = 0.002;           // s: log time - stamp, all but the images
constexpr double kImageDelay = 0.005;           // s: log time - stamp, images
const Vector3d kJointOrigin(0.10, 0.0, 0.30);   // m: a point on the pan axis, in base_link
const Vector3d kJointAxis(0, 0, 1);             // the pan axis in base_link
constexpr double kWheelRadius = 0.05, kWheelTrack = 0.30; // m: the wheels' plausible readings
const char *const kOdom = "odom", *const kBase = "base_link", *const kCamera = "camera_optical";
const char *const kPan = "pan_link"; // --pan-in-tf's joint child

/* Rotation about +z by a (right-handed, REP 103: positive turns x toward y, i.e. LEFT). */
Matrix3d rotZ(double a)
{
  Matrix3d R;
  R << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return R;
}

/* The axis permutation from yawdepth's vision axes (x right, y down, z forward) to base_link's
   (x forward, y left, z up) for a camera looking LEFT of the robot and the robot driving along its
   image's +x: columns are v's axes in base_link: v_x = b_x, v_y (down) = -b_z, v_z (look) = +b_y. */
Matrix3d bRv()
{
  Matrix3d R;
  R << 1, 0, 0, //
      0, 0, 1,  //
      0, -1, 0;
  return R;
}

Isometry3d pose(const Matrix3d &R, const Vector3d &t)
{
  Isometry3d M = Isometry3d::Identity();
  M.linear() = R;
  M.translation() = t;
  return M;
}

/* odomMw': the drive's world in odom. w' is v at t = 0, where base_link = odom (heading 0, x 0): its
   axes are bRv(), its origin the pan axis point kJointOrigin (z = 0.30 m above the floor). */
Isometry3d odomMw() { return pose(bRv(), kJointOrigin); }

/* base_link's pose in odom for a drive row (x, heading): the robot's REP 103 yaw psi = -heading
   (heading turns about v's +Y = down = -z); the pan axis point moves along odom's +x (the drive's
   x along w' x = odom x), 0.30 m up; base_link sits kJointOrigin behind/below it, on the floor. */
Isometry3d odomMb(const yawdepth::MotionSample &s)
{
  const double psi = -s.heading;
  const Vector3d odom_p_pan = kJointOrigin + Vector3d(s.x, 0, 0);
  return pose(rotZ(psi), odom_p_pan - rotZ(psi) * kJointOrigin);
}

/* bMpan(q): the pan frame at joint position q (base_link's axes turned by q about +z, its origin on
   the axis). panMc: camera_optical in the pan frame, the rig's yaw-0 mount (v's axes, the optical
   centre at t0 = (-0.05, 0, 0) in v, i.e. 5 cm behind the axis along base_link's -x). */
Isometry3d bMpan(double q) { return pose(rotZ(q), kJointOrigin); }
Isometry3d panMc(const yawdepth::YawRig &rig) { return pose(bRv(), bRv() * rig.cameraOffset()); }

Isometry3d toEigen(const vpHomogeneousMatrix &M)
{
  Isometry3d E = Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      E(i, j) = M[unsigned(i)][unsigned(j)];
    E(i, 3) = M[unsigned(i)][3];
  }
  return E;
}

ros::Time rosTime(double t)
{
  ros::Time r;
  r.fromNSec(std::uint64_t(std::llround(t * 1e9)));
  return r;
}

geometry_msgs::Transform toTransform(const Isometry3d &M)
{
  geometry_msgs::Transform T;
  T.translation.x = M.translation().x();
  T.translation.y = M.translation().y();
  T.translation.z = M.translation().z();
  const Eigen::Quaterniond q(M.linear());
  T.rotation.x = q.x();
  T.rotation.y = q.y();
  T.rotation.z = q.z();
  T.rotation.w = q.w();
  return T;
}

/* One message to write: its log time and how to write it. */
struct Record {
  double log_time;
  int order; // ties keep the order they were made in
  std::function<void(rosbag::Bag &)> write;
};

/* A connection header as a real publisher's (rosbag::Bag writes it as given: the type fields too). */
template <typename M> boost::shared_ptr<ros::M_string> header(const std::string &topic, const std::string &callerid,
                                                              bool latching)
{
  auto h = boost::make_shared<ros::M_string>();
  (*h)["topic"] = topic;
  (*h)["type"] = ros::message_traits::datatype<M>();
  (*h)["md5sum"] = ros::message_traits::md5sum<M>();
  (*h)["message_definition"] = ros::message_traits::definition<M>();
  (*h)["callerid"] = callerid;
  (*h)["latching"] = latching ? "1" : "0";
  return h;
}

/* The shortest text that reads back as `v` exactly. */
std::string num(double v)
{
  char b[40];
  for (int precision = 15; precision <= 17; ++precision) {
    std::snprintf(b, sizeof b, "%.*g", precision, v);
    if (std::strtod(b, nullptr) == v)
      break;
  }
  return b;
}

std::string vec(const Vector3d &v) { return "[" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "]"; }

int usage(const std::string &msg)
{
  std::cerr << "make_drive_bag: " << msg
            << " (usage: make_drive_bag --out BAG --truth JSON [--seconds 6] [--latency 0.030] [--pan-in-tf] "
               "[--raw-images])\n";
  return 2;
}

int main(int argc, char **argv)
{
  std::string out, truth;
  double seconds = 6, latency = 0.030;
  bool pan_in_tf = false, raw_images = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::cout << "make_drive_bag --out BAG --truth JSON [--seconds 6] [--latency 0.030] [--pan-in-tf] "
                   "[--raw-images]\n";
      return 0;
    }
    if (a == "--pan-in-tf" || a == "--raw-images") {
      (a == "--pan-in-tf" ? pan_in_tf : raw_images) = true;
      continue;
    }
    if (i + 1 >= argc)
      return usage(a + ": needs a value");
    const std::string v = argv[++i];
    auto number = [&](double &x, double lo, double hi) {
      char *end = nullptr;
      x = std::strtod(v.c_str(), &end);
      return !v.empty() && *end == '\0' && std::isfinite(x) && x >= lo && x <= hi;
    };
    if (a == "--out")
      out = v;
    else if (a == "--truth")
      truth = v;
    else if (a == "--seconds") {
      if (!number(seconds, 0.5, 600))
        return usage("--seconds " + v + ": give a number from 0.5 to 600");
    } else if (a == "--latency") {
      if (!number(latency, 0, 1))
        return usage("--latency " + v + ": give a number from 0 to 1 (s)");
    } else
      return usage("unknown option " + a);
  }
  if (out.empty() || truth.empty())
    return usage("--out and --truth are required");

  try {
    const drive::Drive d = drive::renderDrive(seconds, kSeed);
    const Isometry3d odomMw_ = odomMw();
    const Isometry3d panMc_ = panMc(d.rig);

    // The check: for every image, odom -> base_link -> pan(q = -yaw) -> camera_optical equals
    // odomMw' * wMc(rig, pose), one constant odomMw' for all images.
    Isometry3d first_odomMw = Isometry3d::Identity();
    double worst = 0;
    for (std::size_t k = 0; k < d.image_poses.size(); ++k) {
      const yawdepth::MotionSample &s = d.image_poses[k];
      const Isometry3d odomMc = odomMb(s) * bMpan(-s.yaw) * panMc_;
      const Isometry3d wMc = toEigen(yawdepth::wMc(d.rig, s));
      const Isometry3d C = odomMc * wMc.inverse(); // odomMw' from this image
      if (k == 0)
        first_odomMw = C;
      worst = std::max({worst, (C.matrix() - first_odomMw.matrix()).cwiseAbs().maxCoeff(),
                        (C.matrix() - odomMw_.matrix()).cwiseAbs().maxCoeff()});
    }
    if (!(worst < 1e-9)) {
      std::cerr << "make_drive_bag: the ROS chain odom->base_link->pan->camera_optical differs from wMc by up to "
                << worst << " from one constant odomMw'\n";
      return 1;
    }

    std::vector<Record> records;
    auto add = [&](double log_time, std::function<void(rosbag::Bag &)> w) {
      records.push_back({log_time, int(records.size()), std::move(w)});
    };

    // /tf_static: the camera's mount at q = 0, bMc0 = bMpan(0) panMc, latched, logged at T0; with
    // --pan-in-tf, the camera on the pan link, panMc.
    {
      tf2_msgs::TFMessage m;
      geometry_msgs::TransformStamped x;
      x.header.stamp = rosTime(kT0);
      x.header.frame_id = pan_in_tf ? kPan : kBase;
      x.child_frame_id = kCamera;
      x.transform = toTransform(pan_in_tf ? panMc_ : bMpan(0) * panMc_);
      m.transforms.push_back(x);
      auto h = header<tf2_msgs::TFMessage>("/tf_static", "/robot_state_publisher", true);
      add(kT0, [m, h](rosbag::Bag &b) { b.write("/tf_static", rosTime(kT0), m, h); });
    }

    // /tf and /odom at 100 Hz: odomMb at each pose time; the twist (child frame base_link) by central
    // differences of the drive's own rows.
    const auto h_tf = header<tf2_msgs::TFMessage>("/tf", "/ekf_odom", false);
    const auto h_odom = header<nav_msgs::Odometry>("/odom", "/ekf_odom", false);
    for (std::size_t i = 0; i < d.poses.size(); ++i) {
      const double t = d.poses[i].first;
      const Isometry3d M = odomMb(d.poses[i].second);
      constexpr double e = 1e-5;
      const Isometry3d Mm = odomMb(drive::truthRow(t - e)), Mp = odomMb(drive::truthRow(t + e));
      const Vector3d odom_v = (Mp.translation() - Mm.translation()) / (2 * e);
      const double psi_dot = (-drive::truthRow(t + e).heading + drive::truthRow(t - e).heading) / (2 * e);
      const Vector3d b_v = M.linear().transpose() * odom_v;
      const ros::Time stamp = rosTime(kT0 + t), logged = rosTime(kT0 + t + kSmallDelay);

      geometry_msgs::TransformStamped x;
      x.header.seq = std::uint32_t(i);
      x.header.stamp = stamp;
      x.header.frame_id = kOdom;
      x.child_frame_id = kBase;
      x.transform = toTransform(M);
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(x);
      add(kT0 + t + kSmallDelay, [tf, logged, h_tf](rosbag::Bag &b) { b.write("/tf", logged, tf, h_tf); });

      nav_msgs::Odometry od;
      od.header = x.header;
      od.child_frame_id = kBase;
      od.pose.pose.position.x = x.transform.translation.x;
      od.pose.pose.position.y = x.transform.translation.y;
      od.pose.pose.position.z = x.transform.translation.z;
      od.pose.pose.orientation = x.transform.rotation;
      od.twist.twist.linear.x = b_v.x();
      od.twist.twist.linear.y = b_v.y();
      od.twist.twist.linear.z = b_v.z();
      od.twist.twist.angular.z = psi_dot;
      for (int r = 0; r < 6; ++r) {
        od.pose.covariance[std::size_t(7 * r)] = r < 3 ? 1e-6 : 1e-5;
        od.twist.covariance[std::size_t(7 * r)] = r < 3 ? 1e-4 : 1e-3;
      }
      add(kT0 + t + kSmallDelay, [od, logged, h_odom](rosbag::Bag &b) { b.write("/odom", logged, od, h_odom); });
    }

    // /joint_states at 50 Hz: the pan's q = -yaw; the wheels of a differential drive of radius 5 cm
    // and track 30 cm (their angles from the distance driven and the robot's yaw psi).
    const auto h_js = header<sensor_msgs::JointState>("/joint_states", "/joint_state_publisher", false);
    const auto h_pan = header<tf2_msgs::TFMessage>("/tf", "/robot_state_publisher", false); // --pan-in-tf
    for (std::size_t i = 0; i < d.joints.size(); ++i) {
      const double t = d.joints[i].first, q = -d.joints[i].second;
      constexpr double e = 1e-5;
      const double psi = -drive::truthRow(t).heading, dist = drive::truthRow(t).x;
      const double psi_dot = (-drive::truthRow(t + e).heading + drive::truthRow(t - e).heading) / (2 * e);
      const double dist_dot = (drive::truthRow(t + e).x - drive::truthRow(t - e).x) / (2 * e);
      const double q_dot = -(drive::truthRow(t + e).yaw - drive::truthRow(t - e).yaw) / (2 * e);
      sensor_msgs::JointState js;
      js.header.seq = std::uint32_t(i);
      js.header.stamp = rosTime(kT0 + t);
      js.name = {"left_wheel", "pan_joint", "right_wheel"};
      js.position = {(dist - psi * kWheelTrack / 2) / kWheelRadius, q, (dist + psi * kWheelTrack / 2) / kWheelRadius};
      js.velocity = {(dist_dot - psi_dot * kWheelTrack / 2) / kWheelRadius, q_dot,
                     (dist_dot + psi_dot * kWheelTrack / 2) / kWheelRadius};
      js.effort = {0.0, 0.0, 0.0};
      const ros::Time logged = rosTime(kT0 + t + kSmallDelay);
      add(kT0 + t + kSmallDelay, [js, logged, h_js](rosbag::Bag &b) { b.write("/joint_states", logged, js, h_js); });
      if (pan_in_tf) { // robot_state_publisher: the joint's transform at the joint state's stamp, on /tf
        geometry_msgs::TransformStamped x;
        x.header.stamp = js.header.stamp;
        x.header.frame_id = kBase;
        x.child_frame_id = kPan;
        x.transform = toTransform(bMpan(q));
        tf2_msgs::TFMessage tf;
        tf.transforms.push_back(x);
        const ros::Time tf_logged = rosTime(kT0 + t + 2 * kSmallDelay); // after the joint state it comes from
        add(kT0 + t + 2 * kSmallDelay,
            [tf, tf_logged, h_pan](rosbag::Bag &b) { b.write("/tf", tf_logged, tf, h_pan); });
      }
    }

    // The images (JPEG 90, image_transport's compressed format string) and camera_info, stamped at
    // the capture's motion time (camera time + drive::kTimeOffset) + latency.
    const auto h_img = header<sensor_msgs::CompressedImage>("/camera/image_raw/compressed", "/camera/camera_driver", false);
    const auto h_raw = header<sensor_msgs::Image>("/camera/image_raw", "/camera/camera_driver", false); // --raw-images
    const auto h_info = header<sensor_msgs::CameraInfo>("/camera/camera_info", "/camera/camera_driver", false);
    std::vector<double> image_stamps;
    for (std::size_t k = 0; k < d.images.size(); ++k) {
      const double capture = d.image_times[k] + drive::kTimeOffset, stamp = kT0 + capture + latency;
      image_stamps.push_back(stamp);
      sensor_msgs::CompressedImage im;
      im.header.seq = std::uint32_t(k);
      im.header.stamp = rosTime(stamp);
      im.header.frame_id = kCamera;
      im.format = "mono8; jpeg compressed mono8";
      if (!cv::imencode(".jpg", d.images[k], im.data, {cv::IMWRITE_JPEG_QUALITY, 90}))
        throw std::runtime_error("JPEG encoding failed");
      const ros::Time im_logged = rosTime(stamp + kImageDelay);
      if (raw_images) {
        sensor_msgs::Image raw;
        raw.header = im.header;
        raw.height = std::uint32_t(d.images[k].rows);
        raw.width = std::uint32_t(d.images[k].cols);
        raw.encoding = "mono8";
        raw.is_bigendian = 0;
        raw.step = std::uint32_t(d.images[k].cols);
        for (int r = 0; r < d.images[k].rows; ++r)
          raw.data.insert(raw.data.end(), d.images[k].ptr<unsigned char>(r),
                          d.images[k].ptr<unsigned char>(r) + d.images[k].cols);
        add(stamp + kImageDelay, [raw, im_logged, h_raw](rosbag::Bag &b) {
          b.write("/camera/image_raw", im_logged, raw, h_raw);
        });
      } else {
        add(stamp + kImageDelay, [im, im_logged, h_img](rosbag::Bag &b) {
          b.write("/camera/image_raw/compressed", im_logged, im, h_img);
        });
      }
      sensor_msgs::CameraInfo info;
      info.header = im.header;
      info.width = drive::kWidth;
      info.height = drive::kHeight;
      info.distortion_model = "plumb_bob";
      info.D = {0, 0, 0, 0, 0};
      info.K = {drive::kFocal, 0, drive::kU0, 0, drive::kFocal, drive::kV0, 0, 0, 1};
      info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
      info.P = {drive::kFocal, 0, drive::kU0, 0, 0, drive::kFocal, drive::kV0, 0, 0, 0, 1, 0};
      const ros::Time info_logged = rosTime(stamp + kSmallDelay);
      add(stamp + kSmallDelay, [info, info_logged, h_info](rosbag::Bag &b) {
        b.write("/camera/camera_info", info_logged, info, h_info);
      });
    }

    std::stable_sort(records.begin(), records.end(), [](const Record &a, const Record &b) {
      return a.log_time < b.log_time || (a.log_time == b.log_time && a.order < b.order);
    });
    {
      rosbag::Bag bag(out, rosbag::bagmode::Write);
      bag.setCompression(rosbag::compression::Uncompressed);
      for (const Record &r : records)
        r.write(bag);
      bag.close();
    }

    // The truth: the wall (Z = kWallDepth in the first image's camera) in odom, n.p = d, and every
    // image's camera pose in odom (odomMw' wMc) at its capture time.
    const Isometry3d odomMc0 = odomMw_ * toEigen(yawdepth::wMc(d.rig, d.image_poses.front()));
    const Vector3d n = odomMc0.linear() * Vector3d::UnitZ();
    const double wall_d = n.dot(odomMc0.translation()) + drive::kWallDepth;
    std::ofstream j(truth);
    j << "{\n  \"seed\": " << kSeed << ", \"seconds\": " << num(seconds) << ", \"T0\": " << num(kT0)
      << ", \"latency\": " << num(latency) << ", \"camera_time_offset\": " << num(drive::kTimeOffset) << ",\n"
      << "  \"frames\": {\"world\": \"" << kOdom << "\", \"body\": \"" << kBase << "\", \"camera\": \"" << kCamera
      << "\"},\n"
      << "  \"joint\": {\"name\": \"pan_joint\", \"axis\": " << vec(kJointAxis) << ", \"origin\": " << vec(kJointOrigin)
      << ", \"position\": \"-yaw of the drive\"},\n"
      << "  \"intrinsics\": {\"width\": " << drive::kWidth << ", \"height\": " << drive::kHeight
      << ", \"fx\": " << num(drive::kFocal) << ", \"fy\": " << num(drive::kFocal) << ", \"cx\": " << num(drive::kU0)
      << ", \"cy\": " << num(drive::kV0) << "},\n"
      << "  \"wall\": {\"frame\": \"odom\", \"n\": " << vec(n) << ", \"d\": " << num(wall_d) << "},\n"
      << "  \"odom_M_drive_world\": {\"t\": " << vec(odomMw_.translation()) << "},\n"
      << "  \"images\": [\n";
    for (std::size_t k = 0; k < d.image_poses.size(); ++k) {
      const Isometry3d odomMc = odomMw_ * toEigen(yawdepth::wMc(d.rig, d.image_poses[k]));
      const Eigen::Quaterniond q(odomMc.linear());
      j << "    {\"index\": " << k << ", \"stamp\": " << num(image_stamps[k])
        << ", \"capture_time\": " << num(kT0 + d.image_times[k] + drive::kTimeOffset)
        << ", \"t\": " << vec(odomMc.translation()) << ", \"q\": [" << num(q.x()) << ", " << num(q.y()) << ", "
        << num(q.z()) << ", " << num(q.w()) << "]}" << (k + 1 < d.image_poses.size() ? ",\n" : "\n");
    }
    j << "  ]\n}\n";
    if (!j.flush())
      throw std::runtime_error(truth + ": cannot write");

    std::cout << "make_drive_bag: " << out << ": " << records.size() << " messages (" << d.images.size()
              << " images, " << d.poses.size() << " poses, " << d.joints.size()
              << " joint readings); chain check max |diff| " << worst << "; truth " << truth << "\n";
  } catch (const std::exception &e) {
    std::cerr << "make_drive_bag: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
