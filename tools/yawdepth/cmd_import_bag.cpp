// `yawdepth import-bag`: a ROS 1 or ROS 2 bag written as the files every command reads (images/,
// motion.csv, camera.yaml, rig.yaml); the bag options are shared with `measure --bag`.
#include "commands.h"
#include "progress.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <yawdepth/bag/import.h>
#include <yawdepth/error.h>

namespace yawdepth::cli {

BagImportOptions BagOptions::options(const std::string &bag, const std::string &out_dir, double time_offset,
                                     double max_pose_gap) const
{
  BagImportOptions o = import;
  o.bag = bag;
  o.out_dir = out_dir;
  o.time_offset = time_offset;
  o.max_pose_gap = max_pose_gap;
  if (!joint_axis.empty())
    std::copy(joint_axis.begin(), joint_axis.end(), o.joint_axis.begin());
  if (!joint_origin.empty())
    std::copy(joint_origin.begin(), joint_origin.end(), o.joint_origin.begin());
  if (!tf.empty()) {
    const std::size_t colon = tf.find(':');
    if (colon == std::string::npos || tf.find(':', colon + 1) != std::string::npos)
      throw Error("--tf " + tf + ": give WORLD:BODY, two frame names");
    o.tf_world = tf.substr(0, colon);
    o.tf_body = tf.substr(colon + 1);
    if (o.tf_world.empty() || o.tf_body.empty())
      throw Error("--tf " + tf + ": give WORLD:BODY, two frame names");
  }
  return o;
}

void addBagOptions(CLI::App *sub, BagOptions &b)
{
  BagImportOptions &o = b.import;
  sub->add_option("--image-topic", o.image_topic,
                  "The images: sensor_msgs/Image (mono8, rgb8, bgr8, mono16) or sensor_msgs/CompressedImage (jpeg, png)");
  sub->add_option("--camera-info-topic", o.camera_info_topic,
                  "The camera's sensor_msgs/CameraInfo (default: the image topic's sibling camera_info; for "
                  "/ns/image_raw/compressed, /ns/camera_info)");
  sub->add_option("--odom-topic", o.odom_topic, "The motion: nav_msgs/Odometry (child_frame_id's pose in frame_id)");
  sub->add_option("--pose-topic", o.pose_topic,
                  "The motion: geometry_msgs/PoseStamped or PoseWithCovarianceStamped (the body: the root of the "
                  "camera frame's /tf_static tree)");
  sub->add_option("--tf", b.tf, "The motion: BODY's pose in WORLD from /tf and /tf_static (WORLD:BODY), chained by tf2");
  sub->add_option("--camera-frame", o.camera_frame,
                  "The camera's frame, its mount in the body from /tf_static (default: the images' frame_id)");
  sub->add_option("--joint-topic", o.joint_topic, "sensor_msgs/JointState with the pan joint (the yaw column)");
  sub->add_option("--joint", o.joint, "The pan joint's name in --joint-topic");
  sub->add_option("--joint-axis", b.joint_axis,
                  "The pan joint's axis in the body, X,Y,Z (default 0,1,0, yawdepth's vision frame; REP 103's z-up "
                  "base_link: 0,0,1)")
      ->delimiter(',')
      ->expected(3)
      ->check(Finite);
  sub->add_option("--joint-origin", b.joint_origin,
                  "A point on the pan joint's axis, in the body, X,Y,Z (m; default 0,0,0; from the robot's URDF)")
      ->delimiter(',')
      ->expected(3)
      ->check(Finite);
  sub->add_option("--start", o.start, "Seconds after the bag's first message to start at")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--duration", o.duration, "Seconds to read from --start (default: to the end)")
      ->check(FiniteNonNegative);
  sub->add_option("--every", o.every, "Keep every Nth image")->check(CLI::PositiveNumber)->capture_default_str();
}

BagImportResult importCommandBag(const std::string &command, const BagImportOptions &options, std::ostream *summary)
{
  BagImportResult r;
  {
    ProgressLine progress;
    BagImportOptions o = options;
    o.progress = [&](std::size_t read, std::size_t total) { progress.count(command, read, total, "images read"); };
    r = importBag(o);
  }
  for (const std::string &w : r.warnings)
    warn(command, w);
  if (summary)
    *summary << "read " << options.bag << "\n" << r.summary();
  return r;
}

namespace {

struct ImportBagArgs {
  std::string bag, out_dir;
  BagOptions options;
  double time_offset = 0.0, max_pose_gap = 0.2;
  bool quiet = false;
};

int runImportBag(const ImportBagArgs &a)
{
  const BagImportOptions o = a.options.options(a.bag, a.out_dir, a.time_offset, a.max_pose_gap);
  o.validate();
  checkOutputs({{"BAG", a.bag}}, {{"--out-dir", (std::filesystem::path(a.out_dir) / "motion.csv").string()},
                                  {"--out-dir", (std::filesystem::path(a.out_dir) / "camera.yaml").string()},
                                  {"--out-dir", (std::filesystem::path(a.out_dir) / "rig.yaml").string()}});
  importCommandBag("import-bag", o, a.quiet ? nullptr : &std::cout);
  return 0;
}

} // namespace

Runner addImportBag(CLI::App &app)
{
  auto a = std::make_shared<ImportBagArgs>();
  CLI::App *sub = app.add_subcommand(
      "import-bag", "Write a ROS 1 bag (.bag) or ROS 2 bag (.mcap, .db3, or its folder) as the files every command "
                    "reads: images/ (named by their stamps), motion.csv (each image's pose interpolated at its "
                    "stamp, and the pan joint as yaw), camera.yaml (from camera_info), rig.yaml (the camera's mount "
                    "from /tf_static).");
  sub->add_option("BAG", a->bag, "The bag file, or a ROS 2 bag folder")->required();
  sub->add_option("--out-dir", a->out_dir, "Output folder (created): images/, motion.csv, camera.yaml, rig.yaml")
      ->required();
  addBagOptions(sub, a->options);
  sub->get_option("--image-topic")->required();
  sub->add_option("--time-offset", a->time_offset,
                  "The image stamped t was taken at motion time t + S (s)")
      ->check(Finite)
      ->capture_default_str();
  sub->add_option("--max-pose-gap", a->max_pose_gap,
                  "An image between two poses (or joint readings) further apart than this is skipped (s)")
      ->check(CLI::PositiveNumber & Finite)
      ->capture_default_str();
  addVerbosityOptions(sub, a->quiet, "No summary on standard output");
  return [a]() { return runImportBag(*a); };
}

} // namespace yawdepth::cli
